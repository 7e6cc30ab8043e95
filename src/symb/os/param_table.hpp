// ParamTable: a task type's parameters, each declared once, OROCOS-style:
//
//   os::ParamTable<Mdl2eParams> p;
//   p.add("speed_limit", &Mdl2eParams::speed_limit).range(0.001, 1e6).doc("wheel speeds are clamped to +-this").live();
//
// One line gives the name, the type (from the field's), the default (the field's value in the
// table's default config), the range, the documentation and the field the value sets. From the
// table come the schema (ParamSpec list: the shell's `types`, scenario files, genomes), the
// factory's config (read(): a filled config struct for the type's factory) and the runtime change
// of a `.live()` parameter on a running task (written into the task's own copy of the struct the
// field belongs to, see Task::bind_parameters). Declare a task type with os::declare_task_type()
// (task_type_registry.hpp).
//
// Field types: bool, any integer type (kInt), float or double (kReal), kernel::Duration and
// std::string. A field of another type (an enum, a parsed list) is declared with a ParamCodec that
// says which ParamType it is written as and how to convert; os::choice() makes one for a closed
// set of words. A field of a base class of Config may be declared (&Config::base_field): that is
// how a type's config extends the options struct its task keeps, so that the task can bind its
// options and take live changes there.
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/param.hpp"

namespace symb::os {

namespace detail {

// A distinct address per type, standing in for RTTI (which a microcontroller build may lack).
template <class T>
const void* type_tag() {
  static constexpr char tag = 0;
  return &tag;
}

template <class T>
constexpr ParamType param_type_of() {
  if constexpr (std::is_same_v<T, bool>)
    return ParamType::kBool;
  else if constexpr (std::is_integral_v<T>)
    return ParamType::kInt;
  else if constexpr (std::is_floating_point_v<T>)
    return ParamType::kReal;
  else if constexpr (std::is_same_v<T, kernel::Duration>)
    return ParamType::kDuration;
  else {
    static_assert(std::is_same_v<T, std::string>, "declare a field of this type with a ParamCodec");
    return ParamType::kString;
  }
}

template <class T>
ParamValue to_param_value(const T& v) {
  if constexpr (std::is_same_v<T, bool>)
    return v;
  else if constexpr (std::is_integral_v<T>)
    return static_cast<std::int64_t>(v);
  else if constexpr (std::is_floating_point_v<T>)
    return static_cast<double>(v);
  else
    return v;
}

// The value has passed the schema's type and range checks, so it fits the field.
template <class T>
T from_param_value(const ParamValue& v) {
  if constexpr (std::is_same_v<T, bool>)
    return std::get<bool>(v);
  else if constexpr (std::is_integral_v<T>)
    return static_cast<T>(std::get<std::int64_t>(v));
  else if constexpr (std::is_floating_point_v<T>)
    return static_cast<T>(std::get<double>(v));
  else
    return std::get<T>(v);
}

}  // namespace detail

// How a field of type T is written as a parameter: its ParamType, the conversion of a checked value
// (may fail: the error is the whole message, name the parameter in it) and back (for the default).
template <class T>
struct ParamCodec {
  ParamType type = ParamType::kString;
  std::function<kernel::Result<T>(const ParamValue&)> parse;
  std::function<ParamValue(const T&)> format;
};

// A codec for a string parameter that takes one of a few words, each standing for a value:
// choice<OdometryFormat>("odometry", {{"pose", kPose}, {"wheels", kWheelDistances}}). An unknown
// word is refused with "odometry must be 'pose' or 'wheels', not 'x'".
template <class T>
ParamCodec<T> choice(std::string param, std::vector<std::pair<std::string, T>> words) {
  auto shared = std::make_shared<const std::vector<std::pair<std::string, T>>>(std::move(words));
  ParamCodec<T> c;
  c.type = ParamType::kString;
  c.parse = [param = std::move(param), shared](const ParamValue& v) -> kernel::Result<T> {
    const auto& word = std::get<std::string>(v);
    std::string all;
    for (std::size_t i = 0; i < shared->size(); ++i) {
      if ((*shared)[i].first == word) return (*shared)[i].second;
      all += (i == 0 ? "'" : i + 1 == shared->size() ? " or '" : ", '") + (*shared)[i].first + "'";
    }
    return kernel::Error{param + " must be " + all + ", not '" + word.substr(0, 63) + "'"};
  };
  c.format = [shared](const T& v) -> ParamValue {
    for (const auto& [w, x] : *shared)
      if (x == v) return w;
    return shared->front().first;
  };
  return c;
}

// How a running task takes a new value of one parameter (TaskType::live, one per schema entry).
struct LiveParam {
  // The struct type the parameter's field belongs to; the task must have bound one of these.
  const void* owner = nullptr;
  // Writes `value` into the bound struct at `object`, then calls `changed`; when either fails the
  // struct is put back as it was and the error returned.
  std::function<kernel::Status(void* object, const ParamValue& value, const std::function<kernel::Status()>& changed)>
      apply;
};

template <class Config>
class ParamTable {
  struct Entry {
    ParamSpec spec;
    std::function<kernel::Status(Config&, const ParamValue&)> read;
    LiveParam live_param;  // apply is set from the start; kept only when declared live
    bool live = false;
  };

 public:
  // A handle on the entry add() just made, to chain the rest of its declaration.
  class Decl {
   public:
    // Inclusive bounds: of the number, of a duration in seconds, of a string's length.
    Decl& range(double lo, double hi) {
      e().spec.min = lo;
      e().spec.max = hi;
      return *this;
    }
    // An upper bound only (a string's longest length, with no shortest).
    Decl& at_most(double hi) {
      e().spec.max = hi;
      return *this;
    }
    Decl& doc(std::string text) {
      e().spec.doc = std::move(text);
      return *this;
    }
    // A running task takes a new value (on its own context, Task::on_parameter_changed after).
    Decl& live() {
      e().live = true;
      return *this;
    }
    // The schema's default when it is not the field's value in the table's default config.
    Decl& default_value(ParamValue v) {
      e().spec.default_value = std::move(v);
      return *this;
    }

   private:
    friend class ParamTable;
    Decl(ParamTable* t, std::size_t i) : table_(t), index_(i) {}
    Entry& e() { return table_->entries_[index_]; }
    ParamTable* table_;
    std::size_t index_;
  };

  // `defaults` gives every parameter's default (the fields' values).
  explicit ParamTable(Config defaults = {}) : defaults_(std::move(defaults)) {}

  // Declares the parameter `name` that sets `field` (of Config or of one of its bases).
  template <class T, class Owner>
  requires std::is_base_of_v<Owner, Config> Decl add(std::string name, T Owner::*field) {
    return add(std::move(name), field, plain_codec<T>());
  }

  template <class T, class Owner>
  requires std::is_base_of_v<Owner, Config> Decl add(std::string name, T Owner::*field, ParamCodec<T> codec) {
    return add_at<Owner, T>(
        std::move(name), [field](Owner& o) -> T& { return o.*field; }, std::move(codec));
  }

  // Declares a parameter that sets a member of a member: add("goal_x", &Options::goal, &Point::x).
  template <class T, class Part, class Owner>
  requires std::is_base_of_v<Owner, Config> Decl add(std::string name, Part Owner::*part, T Part::*field) {
    return add(std::move(name), part, field, plain_codec<T>());
  }

  template <class T, class Part, class Owner>
  requires std::is_base_of_v<Owner, Config> Decl add(std::string name, Part Owner::*part, T Part::*field,
                                                     ParamCodec<T> codec) {
    return add_at<Owner, T>(
        std::move(name), [part, field](Owner& o) -> T& { return (o.*part).*field; }, std::move(codec));
  }

  // The schema, in declaration order.
  std::vector<ParamSpec> specs() const {
    std::vector<ParamSpec> out;
    for (const auto& e : entries_) out.push_back(e.spec);
    return out;
  }
  // How a running task takes each parameter, in declaration order (no apply: it cannot).
  std::vector<LiveParam> live_params() const {
    std::vector<LiveParam> out;
    for (const auto& e : entries_) out.push_back(e.live ? e.live_param : LiveParam{});
    return out;
  }
  // The default config with every resolved value written in (`values` comes from
  // TaskTypeRegistry::resolve: every parameter is there, checked against its schema entry).
  kernel::Result<Config> read(const ParamSet& values) const {
    Config c = defaults_;
    for (const auto& e : entries_) {
      const ParamValue* v = values.find(e.spec.name);
      if (v == nullptr) return kernel::Error{"parameter '" + e.spec.name + "' has no value"};
      if (auto st = e.read(c, *v); !st) return kernel::Error{st.error()};
    }
    return c;
  }

 private:
  template <class T>
  static ParamCodec<T> plain_codec() {
    ParamCodec<T> c;
    c.type = detail::param_type_of<T>();
    c.parse = [](const ParamValue& v) -> kernel::Result<T> { return detail::from_param_value<T>(v); };
    c.format = [](const T& v) { return detail::to_param_value<T>(v); };
    return c;
  }

  // The one place an entry is made: `at` finds the field in its owner struct.
  template <class Owner, class T, class At>
  Decl add_at(std::string name, At at, ParamCodec<T> codec) {
    Entry e;
    e.spec.name = std::move(name);
    e.spec.type = codec.type;
    Owner& d = static_cast<Owner&>(defaults_);
    e.spec.default_value = codec.format(at(d));
    auto parse = std::make_shared<const std::function<kernel::Result<T>(const ParamValue&)>>(std::move(codec.parse));
    e.read = [at, parse](Config& c, const ParamValue& v) -> kernel::Status {
      auto x = (*parse)(v);
      if (!x) return kernel::Error{x.error()};
      at(static_cast<Owner&>(c)) = std::move(x).value();
      return {};
    };
    e.live_param.owner = detail::type_tag<Owner>();
    e.live_param.apply = [at, parse](void* object, const ParamValue& v,
                                     const std::function<kernel::Status()>& changed) -> kernel::Status {
      auto x = (*parse)(v);
      if (!x) return kernel::Error{x.error()};
      T& field = at(*static_cast<Owner*>(object));
      T before = field;
      field = std::move(x).value();
      kernel::Status st = changed();
      if (!st) field = std::move(before);
      return st;
    };
    entries_.push_back(std::move(e));
    return Decl(this, entries_.size() - 1);
  }

  Config defaults_;
  std::vector<Entry> entries_;
};

}  // namespace symb::os
