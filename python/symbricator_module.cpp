// The Python module `symbricator` (pybind11; docs/python.md): a scenario run in virtual time as
// `symb run` runs it (the lockstep executor on one thread, the same trajectory hash), driven in
// steps or to its end from Python; its results as numpy arrays, each built in one copy of the
// recorded block (never element by element); its robots' nodes changed while they run (create,
// hook, suspend, parameters, messages, any shell line); task types and tasks written in Python
// (the slow path: every handler takes the GIL); and the (1+1)-ONLINE algorithm as a pure state
// machine a Python loop can drive. C++ errors arrive as symbricator.Error with their located text.
//
// The GIL: run() and step() release it while the executor runs, and a Python task's handler takes
// it for its own call, so a Python task works whichever thread the executor calls it from.
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "symb/apps/run/run_recorder.hpp"
#include "symb/evo/mu_plus_one/mu_plus_one.hpp"
#include "symb/evo/one_plus_one/one_plus_one.hpp"
#include "symb/io/plugin_library.hpp"
#include "symb/kernel/lockstep_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace py = pybind11;
using namespace symb;

namespace {

// What becomes symbricator.Error: the C++ error's text, location included, unchanged.
struct SymbError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

template <class T>
T value_or_raise(kernel::Result<T> r) {
  if (!r) throw SymbError(r.error());
  return std::move(r).value();
}

void raise_if(const kernel::Status& s) {
  if (!s) throw SymbError(s.error());
}

double seconds(kernel::Time t) { return std::chrono::duration<double>(t).count(); }
kernel::Duration duration_of(double s) {
  return std::chrono::duration_cast<kernel::Duration>(std::chrono::duration<double>(s));
}

// ---- Python tasks -------------------------------------------------------------------------------

class PyTask;

// What a Python handler is given: the task's services, valid while the task lives (a handle kept
// longer raises instead of reaching a deleted task).
struct TaskContext {
  PyTask* task = nullptr;
  PyTask& get() const {
    if (task == nullptr) throw SymbError("this task is gone");
    return *task;
  }
};

// A task whose handlers are a Python object's methods (on_start, on_message, on_tick, on_stop;
// each optional). An exception in one faults this task only (the node logs it and goes on).
class PyTask : public os::Task {
 public:
  explicit PyTask(py::object obj) : obj_(std::move(obj)), ctx_(std::make_shared<TaskContext>()) { ctx_->task = this; }
  ~PyTask() override {
    ctx_->task = nullptr;
    py::gil_scoped_acquire gil;
    obj_ = py::object();
    ctx_py_ = py::object();
  }

  using os::Task::name;
  using os::Task::now;
  using os::Task::probe;
  using os::Task::send;
  void log_info(const std::string& text) const { log(os::LogLevel::kInfo, text); }

 protected:
  void on_start() override { call("on_start"); }
  void on_tick() override { call("on_tick"); }
  void on_stop() override { call("on_stop"); }
  void on_message(const os::Message& m) override { call("on_message", &m); }

 private:
  // `m`: the message for on_message (handed on as port and a list of floats), null for the others.
  void call(const char* handler, const os::Message* m = nullptr) {
    std::string error;
    {
      py::gil_scoped_acquire gil;
      try {
        if (!py::hasattr(obj_, handler)) return;
        if (!ctx_py_) ctx_py_ = py::cast(ctx_);
        if (m != nullptr) {
          const auto v = m->numbers();
          py::list values(v.size());
          for (std::size_t i = 0; i < v.size(); ++i) values[i] = py::float_(v[i]);
          obj_.attr(handler)(ctx_py_, m->port, values);
        } else {
          obj_.attr(handler)(ctx_py_);
        }
      } catch (py::error_already_set& e) {
        error = e.what();  // the exception's type and text; freed here, under the GIL
      }
    }
    if (!error.empty()) throw std::runtime_error("Python: " + error);
  }

  py::object obj_;
  std::shared_ptr<TaskContext> ctx_;
  py::object ctx_py_;
};

// A task type whose tasks are made by calling a Python class (or any callable) without arguments;
// its `period` attribute (seconds), when it has one, is the type's default tick period.
os::TaskType python_task_type(const std::string& name, py::object factory) {
  std::string doc = "Python task type";
  if (py::hasattr(factory, "__doc__") && !factory.attr("__doc__").is_none())
    doc = py::str(factory.attr("__doc__")).cast<std::string>();
  std::optional<double> period;
  if (py::hasattr(factory, "period")) period = factory.attr("period").cast<double>();
  auto shared = std::make_shared<py::object>(std::move(factory));
  auto t = os::declare_task_type(name, doc, os::ParamTable<os::NoParams>{},
                                 [shared](const os::NoParams&) -> kernel::Result<std::unique_ptr<os::Task>> {
                                   py::gil_scoped_acquire gil;
                                   try {
                                     return std::unique_ptr<os::Task>(std::make_unique<PyTask>((*shared)()));
                                   } catch (py::error_already_set& e) {
                                     return kernel::Error{std::string("Python: ") + e.what()};
                                   }
                                 });
  if (period) t.defaults.period = duration_of(*period);
  return t;
}

// ---- a run --------------------------------------------------------------------------------------

// One row per robot and step, the columns below (float64): steps.csv's columns in its order (the
// robot as its index), then the distance travelled.
constexpr const char* kStepColumns[] = {"time_s",    "robot",      "x_cm",    "y_cm",       "heading_rad", "ir0",
                                        "ir1",       "ir2",        "ir3",     "ir4",        "ir5",         "ir6",
                                        "left_cm_s", "right_cm_s", "contact", "distance_cm"};
constexpr std::size_t kStepCols = std::size(kStepColumns);

struct ProbeSeries {
  std::size_t robot;
  std::string task, channel;
  std::vector<double> times;
  std::vector<float> values;  // rows of `width`
  std::size_t width = 0;
};

class Simulation;

struct Robot {
  Simulation* sim;
  std::size_t index;
};

class Simulation {
 public:
  Simulation(const std::string& path, std::optional<std::uint64_t> seed, std::optional<double> duration,
             const std::vector<std::string>& plugins, const py::dict& types) {
    scenario_ = value_or_raise(sim::load_scenario(path));
    if (duration) scenario_.duration = duration_of(*duration);
    executor_ = std::make_unique<kernel::LockstepExecutor>(
        kernel::LockstepExecutor::Options{.threads = 1, .quantum = scenario_.control_period});
    sim::SessionOptions so;
    so.seed = seed;
    for (const std::string& p : plugins) {
      auto lib = value_or_raise(io::PluginLibrary::open(p));
      so.task_types.push_back([lib](os::TaskTypeRegistry& r) { return lib->register_into(r); });
    }
    for (auto [name, factory] : types) {
      auto type = std::make_shared<os::TaskType>(
          python_task_type(name.cast<std::string>(), py::reinterpret_borrow<py::object>(factory)));
      python_types_.push_back(type);
      so.task_types.push_back([type](os::TaskTypeRegistry& r) { return r.add(*type); });
    }
    session_ = value_or_raise(sim::ScenarioSession::create(scenario_, *executor_, so));
    dt_ = std::chrono::duration<double>(scenario_.control_period).count();
    recorder_ = std::make_unique<apps::run::RunRecorder>(session_->world(), nullptr, 1, dt_);
    session_->runner().add_observer([this](const sim::StepRecord& r) { on_step(r); });
    for (std::size_t i = 0; i < session_->robot_count(); ++i)
      session_->robot(i).node().set_probe_sink([this, i](const os::ProbeSample& s) { on_probe(i, s); });
    session_->start();
  }

  ~Simulation() {
    if (!session_) return;
    for (std::size_t i = 0; i < session_->robot_count(); ++i) session_->robot(i).node().set_probe_sink({});
    py::gil_scoped_release release;  // Python tasks' destructors take it themselves
    session_.reset();
  }

  double time() const { return seconds(executor_->now()); }
  double duration() const { return std::chrono::duration<double>(scenario_.duration).count(); }
  std::uint64_t steps_run() const { return recorder_->steps(); }
  std::uint64_t trajectory_hash() const { return recorder_->hash(); }
  const sim::Scenario& scenario() const { return scenario_; }
  sim::ScenarioSession& session() { return *session_; }

  // To the end of the scenario, or `for_seconds` further (never past the end).
  void run(std::optional<double> for_seconds) {
    const kernel::Time end = kernel::Time{} + scenario_.duration;
    kernel::Time until = end;
    if (for_seconds) until = std::min(end, executor_->now() + duration_of(*for_seconds));
    advance(until);
  }
  void step(std::uint64_t n) { advance(executor_->now() + scenario_.control_period * static_cast<std::int64_t>(n)); }

  // The recorded steps, rows x kStepCols, in one copy of the block.
  py::array_t<double> steps() const {
    py::array_t<double> a({static_cast<py::ssize_t>(rows_.size() / kStepCols), static_cast<py::ssize_t>(kStepCols)});
    if (!rows_.empty()) std::memcpy(a.mutable_data(), rows_.data(), rows_.size() * sizeof(double));
    return a;
  }
  // Robot i's poses, steps x [x, y, heading]: one strided pass over the block.
  py::array_t<double> trajectory(std::size_t robot) const {
    const std::size_t robots = session_->robot_count();
    if (robot >= robots) throw py::index_error("no robot " + std::to_string(robot));
    const std::size_t n = rows_.size() / kStepCols / robots;
    py::array_t<double> a({static_cast<py::ssize_t>(n), py::ssize_t{3}});
    double* out = a.mutable_data();
    for (std::size_t s = 0; s < n; ++s)
      std::memcpy(out + 3 * s, rows_.data() + (s * robots + robot) * kStepCols + 2, 3 * sizeof(double));
    return a;
  }
  // {(robot, task, channel): (times [n], values [n x width])}, each array one copy.
  py::dict probes(std::optional<std::string> only_channel) const {
    py::dict d;
    for (const ProbeSeries& s : series_) {
      if (only_channel && s.channel != *only_channel) continue;
      py::array_t<double> t(static_cast<py::ssize_t>(s.times.size()));
      if (!s.times.empty()) std::memcpy(t.mutable_data(), s.times.data(), s.times.size() * sizeof(double));
      py::array_t<float> v({static_cast<py::ssize_t>(s.times.size()), static_cast<py::ssize_t>(s.width)});
      if (!s.values.empty()) std::memcpy(v.mutable_data(), s.values.data(), s.values.size() * sizeof(float));
      d[py::make_tuple(session_->robot(s.robot).name(), s.task, s.channel)] = py::make_tuple(t, v);
    }
    return d;
  }

  Robot robot(const py::object& which) {
    if (py::isinstance<py::int_>(which)) {
      const auto i = which.cast<std::size_t>();
      if (i >= session_->robot_count()) throw py::index_error("no robot " + std::to_string(i));
      return {this, i};
    }
    const auto name = which.cast<std::string>();
    for (std::size_t i = 0; i < session_->robot_count(); ++i)
      if (session_->robot(i).name() == name) return {this, i};
    throw SymbError("the scenario has no robot '" + name + "'");
  }

 private:
  void advance(kernel::Time until) {
    {
      py::gil_scoped_release release;
      executor_->run_until(until);
    }
    if (auto e = session_->cycle_error(); !e.empty()) throw SymbError(e);
  }

  void on_step(const sim::StepRecord& r) {
    recorder_->on_step(r);
    const double t = static_cast<double>(r.step) * dt_;  // as steps.csv's time_s
    for (std::size_t i = 0; i < r.robots.size(); ++i) {
      const sim::RobotStep& s = r.robots[i];
      const double row[kStepCols] = {t,
                                     static_cast<double>(i),
                                     s.state.pose.x,
                                     s.state.pose.y,
                                     s.state.pose.theta,
                                     s.ir[0],
                                     s.ir[1],
                                     s.ir[2],
                                     s.ir[3],
                                     s.ir[4],
                                     s.ir[5],
                                     s.ir[6],
                                     s.state.left_speed,
                                     s.state.right_speed,
                                     s.state.in_contact ? 1.0 : 0.0,
                                     s.state.distance};
      rows_.insert(rows_.end(), std::begin(row), std::end(row));
    }
  }

  void on_probe(std::size_t robot, const os::ProbeSample& s) {
    ProbeSeries* series = nullptr;
    for (ProbeSeries& x : series_)
      if (x.robot == robot && x.task == s.task && x.channel == s.channel && x.width == s.values.size()) series = &x;
    if (series == nullptr) {
      series = &series_.emplace_back();
      *series = ProbeSeries{robot, std::string(s.task), std::string(s.channel), {}, {}, s.values.size()};
    }
    series->times.push_back(seconds(s.time));
    series->values.insert(series->values.end(), s.values.begin(), s.values.end());
  }

  sim::Scenario scenario_;
  // The Python types' factories: held here too, so that their last reference (and the Python
  // object's) goes with the Simulation, under the GIL, not with a registry inside the session.
  std::vector<std::shared_ptr<os::TaskType>> python_types_;
  std::unique_ptr<kernel::LockstepExecutor> executor_;
  std::unique_ptr<sim::ScenarioSession> session_;
  std::unique_ptr<apps::run::RunRecorder> recorder_;
  double dt_ = 0;  // the control period, s
  std::vector<double> rows_;
  std::vector<ProbeSeries> series_;
};

// ---- a live robot -------------------------------------------------------------------------------

os::Node& node_of(const Robot& r) { return r.sim->session().robot(r.index).node(); }

os::TaskId task_id(const Robot& r, const std::string& name) {
  auto id = node_of(r).find(name);
  if (!id) throw SymbError("robot '" + node_of(r).name() + "' has no task '" + name + "'");
  return *id;
}

std::string param_text(const py::handle& v) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  return py::str(v).cast<std::string>();
}

// The algorithms of `symb evolve` for a Python loop: ask next(), run it, report(fitness).
struct PyOnePlusOne {
  std::optional<evo::OnePlusOne> algorithm;
};
struct PyMuPlusOne {
  std::optional<evo::MuPlusOne> algorithm;
};

py::array_t<double> genes_array(const evo::RealGenome& g) {
  py::array_t<double> a(static_cast<py::ssize_t>(g.values.size()));
  std::copy(g.values.begin(), g.values.end(), a.mutable_data());
  return a;
}

}  // namespace

PYBIND11_MODULE(symbricator, m) {
  m.doc() = "Symbricator: scenarios, robots' task graphs, evolution (docs/python.md)";
  m.attr("__version__") = SYMB_VERSION;
  static py::exception<SymbError> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SymbError& e) {
      error(e.what());
    }
  });
  m.attr("STEP_COLUMNS") = py::cast(std::vector<std::string>(std::begin(kStepColumns), std::end(kStepColumns)));

  py::class_<TaskContext, std::shared_ptr<TaskContext>>(m, "TaskContext",
                                                        "A Python task's services, given to its handlers")
      .def(
          "send",
          [](const TaskContext& c, const std::vector<float>& values, os::Port port) { c.get().send(port, values); },
          py::arg("values"), py::arg("port") = 0, "send numbers (at most 32) on a port to every hooked task")
      .def(
          "probe",
          [](const TaskContext& c, const std::string& channel, const std::vector<float>& values) {
            c.get().probe(channel, values);
          },
          py::arg("channel"), py::arg("values"))
      .def("log", [](const TaskContext& c, const std::string& text) { c.get().log_info(text); })
      .def_property_readonly("now", [](const TaskContext& c) { return seconds(c.get().now()); })
      .def_property_readonly("name", [](const TaskContext& c) { return c.get().name(); });

  py::class_<Robot>(m, "Robot", "A robot's node while the run lives")
      .def_property_readonly("name", [](const Robot& r) { return node_of(r).name(); })
      .def(
          "tasks",
          [](const Robot& r) {
            py::list out;
            for (const os::TaskInfo& t : node_of(r).tasks()) {
              py::dict d;
              d["name"] = t.name;
              d["type"] = t.type;
              d["state"] = os::to_string(t.state);
              d["priority"] = t.priority;
              out.append(d);
            }
            return out;
          },
          "the node's tasks: name, type, state, priority")
      .def(
          "create",
          [](const Robot& r, const std::string& type, const std::string& name, const py::kwargs& params) {
            std::vector<os::ParamAssignment> given;
            for (auto [k, v] : params) given.push_back({k.cast<std::string>(), param_text(v), 1});
            value_or_raise(node_of(r).create(type, name, given));
          },
          py::arg("type"), py::arg("name"), "create a task of a registered type: create('mdl2e', 'c2', program=...)")
      .def(
          "add_task",
          [](const Robot& r, const std::string& name, py::object obj, std::optional<double> period) {
            os::TaskOptions o;
            if (period) o.period = duration_of(*period);
            value_or_raise(node_of(r).create(name, std::make_unique<PyTask>(std::move(obj)), o));
          },
          py::arg("name"), py::arg("task"), py::arg("period") = py::none(),
          "add a task whose handlers are `task`'s methods (the slow path)")
      .def(
          "hook",
          [](const Robot& r, const std::string& from, const std::string& to, std::optional<os::Port> port) {
            os::HookOptions o;
            if (port) o.port = *port;
            const os::HookId h = value_or_raise(node_of(r).hook(task_id(r, from), task_id(r, to), o));
            return h.serial;
          },
          py::arg("sender"), py::arg("receiver"), py::arg("port") = py::none(), "hook sender -> receiver")
      .def("unhook",
           [](const Robot& r, const std::string& from, const std::string& to) {
             shell::Shell sh(node_of(r));
             if (auto rep = sh.execute("unhook " + from + " " + to); !rep.ok) throw SymbError(rep.text);
           })
      .def("suspend", [](const Robot& r, const std::string& t) { raise_if(node_of(r).suspend(task_id(r, t))); })
      .def("resume", [](const Robot& r, const std::string& t) { raise_if(node_of(r).resume(task_id(r, t))); })
      .def("remove", [](const Robot& r, const std::string& t) { raise_if(node_of(r).remove(task_id(r, t))); })
      .def("set",
           [](const Robot& r, const std::string& t, const std::string& param, const py::object& value) {
             raise_if(node_of(r).set_parameter(task_id(r, t), param, param_text(value)));
           })
      .def("parameters",
           [](const Robot& r, const std::string& t) {
             py::dict d;
             const os::ParamSet p = value_or_raise(node_of(r).parameters(task_id(r, t)));
             for (const auto& [name, value] : p.values()) d[py::str(name)] = os::format_param_value(value);
             return d;
           })
      .def(
          "post",
          [](const Robot& r, const std::string& t, const std::vector<float>& values, os::Port port) {
            os::Message msg;
            msg.port = port;
            msg.payload = os::Payload(std::span<const float>(values));
            raise_if(node_of(r).post(task_id(r, t), msg));
          },
          py::arg("task"), py::arg("values"), py::arg("port") = 0, "post a message into a task's queue")
      .def(
          "shell",
          [](const Robot& r, const std::string& line) {
            shell::Shell sh(node_of(r));
            shell::Reply rep = sh.execute(line);
            if (!rep.ok) throw SymbError(rep.text.substr(0, rep.text.find_last_not_of('\n') + 1));
            return rep.text;
          },
          "run one shell line (docs/shell.md) on the node; its reply, or symbricator.Error");

  py::class_<Simulation>(m, "Simulation", "A scenario run in virtual time, as `symb run` runs it")
      .def(py::init<const std::string&, std::optional<std::uint64_t>, std::optional<double>,
                    const std::vector<std::string>&, const py::dict&>(),
           py::arg("scenario"), py::arg("seed") = py::none(), py::arg("duration") = py::none(),
           py::arg("plugins") = std::vector<std::string>{}, py::arg("types") = py::dict())
      .def("run", &Simulation::run, py::arg("seconds") = py::none(),
           "run to the end, or `seconds` of simulated time further")
      .def("step", &Simulation::step, py::arg("n") = 1, "run n control periods")
      .def_property_readonly("time", &Simulation::time)
      .def_property_readonly("duration", &Simulation::duration)
      .def_property_readonly("steps_run", &Simulation::steps_run)
      .def_property_readonly("trajectory_hash", &Simulation::trajectory_hash)
      .def_property_readonly("robot_count", [](Simulation& s) { return s.session().robot_count(); })
      .def("steps", &Simulation::steps, "every robot's every step, rows x STEP_COLUMNS (one copy)")
      .def("trajectory", &Simulation::trajectory, py::arg("robot") = 0, "a robot's [x, y, theta] per step")
      .def("probes", &Simulation::probes, py::arg("channel") = py::none(), "{(robot, task, channel): (times, values)}")
      .def(
          "spikes", [](const Simulation& s) { return s.probes(std::string("spikes")); },
          "the spiking networks' spike samples (probes on channel 'spikes')")
      .def("robot", &Simulation::robot, py::keep_alive<0, 1>(), py::arg("which") = 0, "a robot by index or name");

  py::class_<PyOnePlusOne>(m, "OnePlusOne", "(1+1)-ONLINE, the algorithm of `symb evolve`, for a Python loop")
      .def(py::init([](std::size_t genes, double lo, double hi, double sigma, double sigma_min, double sigma_max,
                       double reevaluation, std::uint64_t seed) {
             const evo::OnePlusOneOptions o{genes, lo, hi, sigma, sigma_min, sigma_max, reevaluation};
             PyOnePlusOne p;
             p.algorithm.emplace(value_or_raise(evo::OnePlusOne::create(o, kernel::RandomStream(seed))));
             return p;
           }),
           py::arg("genes"), py::arg("lo") = -4.0, py::arg("hi") = 4.0, py::arg("sigma") = 1.0,
           py::arg("sigma_min") = 1e-4, py::arg("sigma_max") = 4.0, py::arg("reevaluation") = 0.2, py::arg("seed") = 1)
      .def("next", [](const PyOnePlusOne& p) { return genes_array(p.algorithm->next()); })
      .def_property_readonly("champion", [](const PyOnePlusOne& p) { return genes_array(p.algorithm->champion()); })
      .def("report", [](PyOnePlusOne& p, double fitness) { p.algorithm->report(fitness); })
      .def_property_readonly("champion_fitness", [](const PyOnePlusOne& p) { return p.algorithm->champion_fitness(); })
      .def_property_readonly("sigma", [](const PyOnePlusOne& p) { return p.algorithm->sigma(); })
      .def_property_readonly("candidate",
                             [](const PyOnePlusOne& p) { return evo::to_string(p.algorithm->candidate_kind()); });

  py::class_<PyMuPlusOne>(m, "MuPlusOne", "(mu+1)-ONLINE, the other algorithm of `symb evolve`, for a Python loop")
      .def(py::init([](std::size_t genes, double lo, double hi, std::size_t mu, double rho, double sigma,
                       double crossover, std::uint64_t seed) {
             evo::MuPlusOneOptions o;
             o.genes = genes;
             o.lo = lo;
             o.hi = hi;
             o.mu = mu;
             o.rho = rho;
             o.sigma = sigma;
             o.crossover = crossover;
             PyMuPlusOne p;
             p.algorithm.emplace(value_or_raise(evo::MuPlusOne::create(o, kernel::RandomStream(seed))));
             return p;
           }),
           py::arg("genes"), py::arg("lo") = -4.0, py::arg("hi") = 4.0, py::arg("mu") = 10, py::arg("rho") = 0.2,
           py::arg("sigma") = 1.0, py::arg("crossover") = 0.5, py::arg("seed") = 1)
      .def("next", [](const PyMuPlusOne& p) { return genes_array(p.algorithm->next()); })
      .def("report", [](PyMuPlusOne& p, double fitness) { p.algorithm->report(fitness); })
      .def_property_readonly("best_fitness",
                             [](const PyMuPlusOne& p) {
                               if (!p.algorithm->has_best()) throw SymbError("no report yet");
                               return p.algorithm->best().fitness;
                             })
      .def_property_readonly("best",
                             [](const PyMuPlusOne& p) {
                               if (!p.algorithm->has_best()) throw SymbError("no report yet");
                               return genes_array(p.algorithm->best().genome);
                             })
      .def_property_readonly("mean_fitness", [](const PyMuPlusOne& p) { return p.algorithm->mean_fitness(); })
      .def_property_readonly("candidate",
                             [](const PyMuPlusOne& p) { return evo::to_string(p.algorithm->candidate_kind()); });
}
