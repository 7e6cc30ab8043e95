#include "symb/sim/enki_world.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <new>
#include <numbers>
#include <stdexcept>

#include <enki/PhysicalEngine.h>
#include <enki/robots/thymio2/Thymio2.h>

namespace symb::sim {

using kernel::Error;

namespace {

// Guards Enki's process-wide state: Enki::random (motor noise) and the object id counter every
// PhysicalObject constructor bumps. See the header.
std::mutex& enki_mutex() {
  static std::mutex mu;
  return mu;
}

bool finite(double v) { return std::isfinite(v); }

double normalize_angle(double a) {
  a = std::remainder(a, 2 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2 * std::numbers::pi : a;
}

constexpr std::size_t round_up(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }

// Whether Enki's square walls pushed `o` back during the last step. Within a physics step Enki
// moves each body, computes its hull's shape there, resolves object contacts (which recompute the
// shape), then tests that shape's points against the sides (x < 0, x > w, ...) and moves the body
// back inside WITHOUT recomputing the shape or calling collisionEvent(). So after step() the shape
// still shows a point beyond a side exactly when the sides touched the body.
bool touched_sides(const Enki::PhysicalObject& o, double w, double h) {
  if (o.isCylindric()) {
    const double r = o.getRadius();
    return o.pos.x - r < 0 || o.pos.y - r < 0 || o.pos.x + r > w || o.pos.y + r > h;
  }
  for (const Enki::PhysicalObject::Part& part : o.getHull())
    for (const Enki::Point& p : part.getTransformedShape())
      if (p.x < 0 || p.y < 0 || p.x > w || p.y > h) return true;
  return false;
}

}  // namespace

// Enki's Thymio2, counting the steps in which it touched anything. Enki calls collisionEvent()
// for every object-object contact, static walls included (with a null or a wall argument).
class EnkiWorld::Thymio final : public Enki::Thymio2 {
 public:
  // Enki's own IR computation is switched off: its readings go stale (see ir_model.hpp), and
  // IrModel computes them instead after each step.
  Thymio() { localInteractions.clear(); }

  bool touched = false;

 protected:
  void collisionEvent(Enki::PhysicalObject* /*other*/) override { touched = true; }
};

// A bump allocator over one address range reserved with mmap when the world is made. Pages are
// committed by the kernel only when first touched, so reserving room for thousands of robots
// costs address space, not memory. Objects are never moved or freed one by one: they all go when
// the arena goes, newest first.
class EnkiWorld::Arena {
 public:
  explicit Arena(std::size_t bytes) : size_(round_up(std::max<std::size_t>(bytes, 1), 4096)) {
    void* p = mmap(nullptr, size_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED)
      throw std::length_error("enki world: cannot reserve " + std::to_string(size_ >> 20) +
                              " MiB of address space for its objects (lower Options::max_robots)");
    base_ = static_cast<unsigned char*>(p);
  }
  ~Arena() {
    for (std::size_t i = objects_.size(); i-- > 0;) objects_[i]->~PhysicalObject();
    munmap(base_, size_);
  }
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  bool has_room(std::size_t bytes) const { return used_ + round_up(bytes, kAlign) <= size_; }

  template <class T>
  T* make() {
    if (!has_room(sizeof(T))) throw std::length_error("enki world: object arena full");
    T* object = new (base_ + used_) T();
    used_ += round_up(sizeof(T), kAlign);
    objects_.push_back(object);
    return object;
  }

 private:
  static constexpr std::size_t kAlign = 64;  // >= alignof of every Enki object
  std::size_t size_;
  unsigned char* base_ = nullptr;
  std::size_t used_ = 0;
  std::vector<Enki::PhysicalObject*> objects_;
};

struct EnkiWorld::EnkiState {
  EnkiState(double w, double h) : world(w, h) {}
  Enki::World world;  // its square walls are the arena's sides; inner walls are objects
};

kernel::Status EnkiWorld::check_spec(const WorldSpec& spec) {
  if (!finite(spec.width) || !finite(spec.height) || spec.width <= 0 || spec.height <= 0)
    return Error{"world: the arena must have a finite, positive width and height (got " + std::to_string(spec.width) +
                 " x " + std::to_string(spec.height) + ")"};
  if (!finite(spec.wall_height) || spec.wall_height <= 0)
    return Error{"world: wall_height must be finite and positive (got " + std::to_string(spec.wall_height) + ")"};
  for (std::size_t i = 0; i < spec.walls.size(); ++i) {
    const WallSpec& w = spec.walls[i];
    const std::string where = w.where.line > 0 || !w.where.file.empty() ? w.where.str() + ": " : std::string();
    if (!finite(w.x1) || !finite(w.y1) || !finite(w.x2) || !finite(w.y2))
      return Error{where + "wall " + std::to_string(i) + ": coordinates must be finite"};
    if (!finite(w.thickness) || w.thickness <= 0)
      return Error{where + "wall " + std::to_string(i) + ": thickness must be finite and positive (got " +
                   std::to_string(w.thickness) + ")"};
  }
  return {};
}

EnkiWorld::EnkiWorld(WorldSpec spec, std::uint64_t seed, Options options)
    : spec_(std::move(spec)),
      options_(options),
      random_(seed, 0x454e4b49 /* "ENKI" */),
      ir_noise_(seed, 0x4952 /* "IR" */) {
  if (auto st = check_spec(spec_); !st) throw std::invalid_argument(st.error());
  if (options_.physics_oversampling == 0 || options_.physics_oversampling > 100)
    throw std::invalid_argument("enki world: physics_oversampling must be 1..100");
  if (options_.max_robots > (std::size_t{1} << 24)) throw std::invalid_argument("enki world: max_robots above 2^24");

  const std::size_t walls = spec_.walls.size();
  arena_ = std::make_unique<Arena>(walls * round_up(sizeof(Enki::PhysicalObject), 64) +
                                   options_.max_robots * round_up(sizeof(Thymio), 64));
  robots_.reserve(std::min<std::size_t>(options_.max_robots, 1024));

  std::lock_guard lock(enki_mutex());
  enki_ = std::make_unique<EnkiState>(spec_.width, spec_.height);
  // The world does not own the objects: they live in (and die with) the arena.
  enki_->world.takeObjectOwnership = false;

  // Every inner wall a static Enki rectangle; the sides are Enki's square walls (the header says
  // why), so they are in the IR model's walls only.
  std::vector<IrModel::Rect> ir_walls = IrModel::walls_of(spec_);
  for (std::size_t i = 4; i < ir_walls.size(); ++i) {
    const IrModel::Rect& r = ir_walls[i];
    auto* o = arena_->make<Enki::PhysicalObject>();
    o->setRectangular(2 * r.half_length, 2 * r.half_width, spec_.wall_height, -1);
    o->pos = Enki::Point(r.cx, r.cy);
    o->angle = r.angle;
    o->setColor(Enki::Color::gray);
    enki_->world.addObject(o);
    ++wall_count_;
  }
  ir_model_ = std::make_unique<IrModel>(std::move(ir_walls));
}

EnkiWorld::~EnkiWorld() {
  std::lock_guard lock(enki_mutex());
  enki_.reset();  // first: it refers to objects in the arena
  arena_.reset();
}

const EnkiWorld::Robot& EnkiWorld::robot_at(std::size_t robot, const char* what) const {
  if (robot >= robots_.size())
    throw std::out_of_range(std::string("enki world: ") + what + ": no robot " + std::to_string(robot) +
                            " (there are " + std::to_string(robots_.size()) + ")");
  return robots_[robot];
}

std::size_t EnkiWorld::add_robot(const std::string& name, RobotKind kind, const Pose& start) {
  if (kind != RobotKind::kThymio2) throw std::invalid_argument("enki world: robot '" + name + "': unknown kind");
  if (!finite(start.x) || !finite(start.y) || !finite(start.theta))
    throw std::invalid_argument("enki world: robot '" + name + "': start pose must be finite");
  if (start.x < 0 || start.x > spec_.width || start.y < 0 || start.y > spec_.height)
    throw std::invalid_argument("enki world: robot '" + name + "' starts at (" + std::to_string(start.x) + ", " +
                                std::to_string(start.y) + "), outside the arena [0, " + std::to_string(spec_.width) +
                                "] x [0, " + std::to_string(spec_.height) + "]");
  if (robots_.size() >= options_.max_robots || !arena_->has_room(sizeof(Thymio)))
    throw std::length_error("enki world: robot '" + name + "': the world holds at most " +
                            std::to_string(options_.max_robots) + " robots (Options::max_robots)");
  std::lock_guard lock(enki_mutex());
  auto* body = arena_->make<Thymio>();
  body->pos = Enki::Point(start.x, start.y);
  body->angle = start.theta;
  body->leftSpeed = body->rightSpeed = 0;
  enki_->world.addObject(body);
  Robot r;
  r.name = name;
  r.body = body;
  r.state.pose = Pose{start.x, start.y, normalize_angle(start.theta)};
  robots_.push_back(std::move(r));
  return robots_.size() - 1;
}

const std::string& EnkiWorld::robot_name(std::size_t robot) const { return robot_at(robot, "robot_name").name; }

void EnkiWorld::step(double dt) {
  if (!(dt > 0 && dt <= 1))
    throw std::invalid_argument("enki world: step dt must be in (0, 1] s, got " + std::to_string(dt));
  std::lock_guard lock(enki_mutex());
  // Enki's generator restarts from this world's own stream, so what other worlds drew in between
  // changes nothing here. (The C library's rand() feeds only Enki's IR and ground sensors, which
  // are switched off.)
  Enki::random.setSeed(static_cast<unsigned long>(random_.next_u64()));
  for (Robot& r : robots_) r.body->touched = false;
  enki_->world.step(dt, options_.physics_oversampling);
  for (Robot& r : robots_) {
    RobotState& st = r.state;
    const Pose now{r.body->pos.x, r.body->pos.y, normalize_angle(r.body->angle)};
    st.distance += std::hypot(now.x - st.pose.x, now.y - st.pose.y);
    st.pose = now;
    st.in_contact = r.body->touched || touched_sides(*r.body, spec_.width, spec_.height);
    if (st.in_contact) ++st.contact_steps;
  }
  // IR after the bodies have moved, from every robot's new pose; noise drawn in robot order.
  poses_.resize(robots_.size());
  for (std::size_t i = 0; i < robots_.size(); ++i) poses_[i] = robots_[i].state.pose;
  ir_model_->set_robots(poses_);
  for (std::size_t i = 0; i < robots_.size(); ++i) robots_[i].ir = ir_model_->read(i, ir_noise_);
  ++steps_;
  time_ += dt;
}

void EnkiWorld::set_wheels(std::size_t robot, double left, double right) {
  const Robot& r = robot_at(robot, "set_wheels");
  if (std::isnan(left) || std::isnan(right))
    throw std::invalid_argument("enki world: set_wheels: NaN speed for robot '" + r.name + "'");
  left = std::clamp(left, -kMaxWheelSpeed, kMaxWheelSpeed);
  right = std::clamp(right, -kMaxWheelSpeed, kMaxWheelSpeed);
  Robot& mr = robots_[robot];
  mr.body->leftSpeed = left;
  mr.body->rightSpeed = right;
  mr.state.left_speed = left;
  mr.state.right_speed = right;
}

IrReadings EnkiWorld::ir(std::size_t robot) const { return robot_at(robot, "ir").ir; }

RobotState EnkiWorld::state(std::size_t robot) const { return robot_at(robot, "state").state; }

}  // namespace symb::sim
