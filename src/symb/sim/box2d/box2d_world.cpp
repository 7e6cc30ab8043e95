#include "symb/sim/box2d/box2d_world.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numbers>
#include <stdexcept>

#include <box2d/box2d.h>

#include "symb/kernel/parallel_for.hpp"
#include "symb/sim/enki_world.hpp"
#include "symb/sim/ir_model.hpp"

namespace symb::sim {

namespace {

// Box2D is tuned for bodies of 0.1 to 10 of its units and keeps a skin of b2_polygonRadius (0.01
// units) around every polygon, where contacts happen. In decimetres a Thymio is 1.1 units wide,
// the skin is 1 mm (and is taken off the shapes below, so the outlines are exact), and a body's
// broad-phase box has 1 cm to spare, so it leaves the tree only every few steps. In centimetres
// every moving body would be reinserted in every step (about twice the cost at 10,000 robots); in
// metres the skin would be 1 cm.
constexpr double kUnitsPerCm = 0.1;
constexpr double kSkin = b2_polygonRadius;  // units

// Enki's Thymio2 (enki/robots/thymio2/Thymio2.cpp): axle, wheel speed limit (kMaxWheelSpeed in
// world.hpp), motor noise, and hull: an arc of radius 8 cm in front, from -asin(5.5/8) to
// +asin(5.5/8), closed by the two back corners at (-3, +-5.5). Box2D takes at most 8 vertices,
// so the arc keeps 5 of Enki's 11 points (both ends, the nose, halfway between): its chords cut
// at most 0.15 cm inside the arc (Enki's 0.02 cm).
constexpr double kAxle = 9.4;           // cm between the wheels
constexpr double kMotorNoise = 0.027;   // each wheel's speed times 1 +- this, uniform
constexpr double kHullRadius = 8.0;     // cm
constexpr double kHullHalfWidth = 5.5;  // cm
constexpr double kHullBack = 3.0;       // cm behind the axle
constexpr int kArcPoints = 5;
constexpr int kHullPoints = kArcPoints + 2;

// Stream ids: each robot's own motor and IR noise (the robot's index in the low 32 bits).
constexpr std::uint64_t kMotorStream = std::uint64_t{0x4d4f54} << 32;  // "MOT"
constexpr std::uint64_t kIrStream = std::uint64_t{0x4952} << 32;       // "IR"

// Guards Box2D's process-wide state: the contact function table it fills on first use
// (b2Contact::s_initialized) and the statistics counters its distance and time-of-impact
// routines bump on every call (b2_gjkCalls, b2_toiCalls, ...). Nothing of a run's result reads
// them, but two worlds stepping on two threads would race on them. See the header.
std::mutex& box2d_mutex() {
  static std::mutex mu;
  return mu;
}

// Into (-pi, pi].
double box2d_angle(double a) {
  a = std::remainder(a, 2 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2 * std::numbers::pi : a;
}

// The convex polygon `v` (counter-clockwise) with every edge moved inwards by `d`: Box2D's skin
// then puts the contact surface back on the original outline.
std::array<b2Vec2, kHullPoints> inset(const std::array<b2Vec2, kHullPoints>& v, double d) {
  std::array<b2Vec2, kHullPoints> out{};
  const std::size_t n = v.size();
  auto normal = [&](std::size_t i) {  // outward normal of the edge v[i] -> v[i + 1]
    const b2Vec2 e = v[(i + 1) % n] - v[i];
    b2Vec2 nrm(e.y, -e.x);
    nrm.Normalize();
    return nrm;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const b2Vec2 n1 = normal((i + n - 1) % n), n2 = normal(i);
    const double k = d / (1 + b2Dot(n1, n2));
    out[i] = v[i] - static_cast<float>(k) * (n1 + n2);
  }
  return out;
}

b2PolygonShape thymio_shape() {
  std::array<b2Vec2, kHullPoints> v{};
  const double a1 = std::asin(kHullHalfWidth / kHullRadius);
  for (int i = 0; i < kArcPoints; ++i) {
    const double a = -a1 + 2 * a1 * i / (kArcPoints - 1);
    v[i].Set(static_cast<float>(kHullRadius * std::cos(a) * kUnitsPerCm),
             static_cast<float>(kHullRadius * std::sin(a) * kUnitsPerCm));
  }
  v[kArcPoints].Set(static_cast<float>(-kHullBack * kUnitsPerCm), static_cast<float>(kHullHalfWidth * kUnitsPerCm));
  v[kArcPoints + 1].Set(static_cast<float>(-kHullBack * kUnitsPerCm),
                        static_cast<float>(-kHullHalfWidth * kUnitsPerCm));
  const auto in = inset(v, kSkin);
  b2PolygonShape shape;
  shape.Set(in.data(), static_cast<int32>(in.size()));
  return shape;
}

// A box centred on (cx, cy) cm, half sizes hx along `angle` and hy across, less the skin (a box
// thinner than two skins keeps half its size: walls are at least a few millimetres thick).
b2PolygonShape box(double cx, double cy, double hx, double hy, double angle) {
  auto core = [](double h) { return std::max(h * kUnitsPerCm - kSkin, h * kUnitsPerCm / 2); };
  b2PolygonShape shape;
  shape.SetAsBox(static_cast<float>(core(hx)), static_cast<float>(core(hy)),
                 b2Vec2(static_cast<float>(cx * kUnitsPerCm), static_cast<float>(cy * kUnitsPerCm)),
                 static_cast<float>(angle));
  return shape;
}

// Whether `body` touches anything now (after the step): Box2D's contact list holds the pairs
// whose broad-phase boxes overlap, and its "touching" flag describes the poses before the step's
// move, so each pair is tested at the current poses.
bool touching(const b2Body& body) {
  for (const b2ContactEdge* e = body.GetContactList(); e; e = e->next) {
    const b2Contact* c = e->contact;
    const b2Fixture* a = c->GetFixtureA();
    const b2Fixture* b = c->GetFixtureB();
    if (b2TestOverlap(a->GetShape(), c->GetChildIndexA(), b->GetShape(), c->GetChildIndexB(),
                      a->GetBody()->GetTransform(), b->GetBody()->GetTransform()))
      return true;
  }
  return false;
}

}  // namespace

struct Box2DWorld::Engine {
  explicit Engine(std::vector<IrModel::Rect> ir_walls) : world(b2Vec2(0, 0)), ir_model(std::move(ir_walls)) {}

  b2World world;
  const b2PolygonShape robot_shape = thymio_shape();
  b2Body* walls = nullptr;
  std::vector<b2Body*> bodies;  // by robot index
  IrModel ir_model;
};

// The same rules as Enki's: a spec one backend takes, the other takes too.
kernel::Status Box2DWorld::check_spec(const WorldSpec& spec) { return EnkiWorld::check_spec(spec); }

Box2DWorld::Box2DWorld(WorldSpec spec, std::uint64_t seed) : spec_(std::move(spec)), seed_(seed) {
  if (auto st = check_spec(spec_); !st) throw std::invalid_argument(st.error());
  // Walls as rectangles, for Box2D and the IR model alike, the sides included.
  const std::vector<IrModel::Rect> rects = IrModel::walls_of(spec_);
  std::lock_guard lock(box2d_mutex());
  engine_ = std::make_unique<Engine>(rects);
  b2BodyDef def;  // static
  engine_->walls = engine_->world.CreateBody(&def);
  for (const IrModel::Rect& r : rects) {
    const b2PolygonShape shape = box(r.cx, r.cy, r.half_length, r.half_width, r.angle);
    b2FixtureDef fd;
    fd.shape = &shape;
    fd.friction = 0;
    engine_->walls->CreateFixture(&fd);
  }
}

Box2DWorld::~Box2DWorld() {
  std::lock_guard lock(box2d_mutex());
  engine_.reset();
}

const Box2DWorld::Robot& Box2DWorld::robot_at(std::size_t robot, const char* what) const {
  if (robot >= robots_.size())
    throw std::out_of_range(std::string("box2d world: ") + what + ": no robot " + std::to_string(robot) +
                            " (there are " + std::to_string(robots_.size()) + ")");
  return robots_[robot];
}

std::size_t Box2DWorld::add_robot(const std::string& name, RobotKind kind, const Pose& start) {
  if (kind != RobotKind::kThymio2) throw std::invalid_argument("box2d world: robot '" + name + "': unknown kind");
  if (!std::isfinite(start.x) || !std::isfinite(start.y) || !std::isfinite(start.theta))
    throw std::invalid_argument("box2d world: robot '" + name + "': start pose must be finite");
  if (start.x < 0 || start.x > spec_.width || start.y < 0 || start.y > spec_.height)
    throw std::invalid_argument("box2d world: robot '" + name + "' starts at (" + std::to_string(start.x) + ", " +
                                std::to_string(start.y) + "), outside the arena [0, " + std::to_string(spec_.width) +
                                "] x [0, " + std::to_string(spec_.height) + "]");
  if (robots_.size() >= kMaxBodies)
    throw std::length_error("box2d world: robot '" + name + "': the world holds at most " + std::to_string(kMaxBodies) +
                            " robots");
  const Pose pose{start.x, start.y, box2d_angle(start.theta)};
  std::lock_guard lock(box2d_mutex());
  b2BodyDef def;
  def.type = b2_dynamicBody;
  def.position.Set(static_cast<float>(pose.x * kUnitsPerCm), static_cast<float>(pose.y * kUnitsPerCm));
  def.angle = static_cast<float>(pose.theta);
  // Only the wheels turn a robot: its wheels' grip on the floor holds it against the turning a
  // contact would give a free body. Free to turn, a robot pushing a wall rotates until a flat of
  // its polygonal front lies on it (the round nose is 5 chords here) and then slides sideways
  // along the wall; Enki's robots push on where they are headed.
  def.fixedRotation = true;
  b2Body* body = engine_->world.CreateBody(&def);
  b2FixtureDef fd;
  fd.shape = &engine_->robot_shape;
  fd.density = 1;
  fd.friction = 0;
  body->CreateFixture(&fd);
  // Box2D turns a body about its centre of mass, which for this hull lies 2.4 cm ahead of the
  // axle; a differential drive turns about the middle of its axle (Enki's position). With the
  // centre of mass there, turning on the spot stays on the spot.
  b2MassData mass;
  body->GetMassData(&mass);
  mass.center.SetZero();
  body->SetMassData(&mass);
  engine_->bodies.push_back(body);

  const std::uint64_t index = robots_.size();
  Robot r;
  r.name = name;
  r.state.pose = pose;
  r.motor = kernel::RandomStream(seed_, kMotorStream | index);
  r.ir_noise = kernel::RandomStream(seed_, kIrStream | index);
  robots_.push_back(std::move(r));
  poses_.push_back(pose);
  return robots_.size() - 1;
}

const std::string& Box2DWorld::robot_name(std::size_t robot) const { return robot_at(robot, "robot_name").name; }

void Box2DWorld::step(double dt) {
  if (!(dt > 0 && dt <= 1))
    throw std::invalid_argument("box2d world: step dt must be in (0, 1] s, got " + std::to_string(dt));
  if (begun_dt_ > 0) {
    if (dt != begun_dt_)
      throw std::invalid_argument("box2d world: step of " + std::to_string(dt) + " s after a step of " +
                                  std::to_string(begun_dt_) + " s was begun");
    begun_dt_ = 0;
  } else {
    advance(dt);
  }
  settle();
  read_ir();  // outside the lock: IrModel is this world's own
  ++steps_;
  time_ += dt;
}

void Box2DWorld::begin_next_step(double dt) {
  if (!(dt > 0 && dt <= 1))
    throw std::invalid_argument("box2d world: step dt must be in (0, 1] s, got " + std::to_string(dt));
  if (begun_dt_ > 0) return;  // begun already: the next step() finishes it
  // Run whole, the next step would move with the speeds set before the step just made (its
  // advance() made them the acting ones). When that step was itself begun early, speeds were set
  // after its advance(): either way the ones to move with are the speeds set so far.
  for (Robot& r : robots_) {
    r.acting_left = r.state.left_speed;
    r.acting_right = r.state.right_speed;
  }
  advance(dt);
  begun_dt_ = dt;
}

void Box2DWorld::advance(double dt) {
  std::lock_guard lock(box2d_mutex());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    Robot& r = robots_[i];
    b2Body* body = engine_->bodies[i];
    const double left = r.acting_left * ((1 - kMotorNoise) + r.motor.uniform(0, 2 * kMotorNoise));
    const double right = r.acting_right * ((1 - kMotorNoise) + r.motor.uniform(0, 2 * kMotorNoise));
    r.acting_left = r.state.left_speed;
    r.acting_right = r.state.right_speed;
    const double forward = (left + right) / 2, turn = (right - left) / kAxle;
    const double heading = body->GetAngle() + turn * dt / 2;
    body->SetLinearVelocity(b2Vec2(static_cast<float>(forward * std::cos(heading) * kUnitsPerCm),
                                   static_cast<float>(forward * std::sin(heading) * kUnitsPerCm)));
    body->SetAngularVelocity(static_cast<float>(turn));
  }
  engine_->world.Step(static_cast<float>(dt), 8, 3);
}

void Box2DWorld::settle() {
  std::lock_guard lock(box2d_mutex());
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    Robot& r = robots_[i];
    b2Body* body = engine_->bodies[i];
    // Box2D's angle is a float that grows with every turn; kept within +-2 pi it keeps its precision.
    if (std::abs(body->GetAngle()) > 2 * std::numbers::pi)
      body->SetTransform(body->GetPosition(), static_cast<float>(box2d_angle(body->GetAngle())));
    const b2Vec2 p = body->GetPosition();
    const Pose now{p.x / kUnitsPerCm, p.y / kUnitsPerCm, box2d_angle(body->GetAngle())};
    RobotState& st = r.state;
    st.distance += std::hypot(now.x - st.pose.x, now.y - st.pose.y);
    st.pose = now;
    poses_[i] = now;
    st.in_contact = touching(*body);
    if (st.in_contact) ++st.contact_steps;
  }
}

void Box2DWorld::read_ir() {
  engine_->ir_model.set_robots(poses_);
  auto read = [this](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) robots_[i].ir = engine_->ir_model.read(i, robots_[i].ir_noise);
  };
  if (parallel_ == nullptr) {
    read(0, robots_.size());
    return;
  }
  parallel_->run(robots_.size(), read);
}

void Box2DWorld::set_wheels(std::size_t robot, double left, double right) {
  const Robot& r = robot_at(robot, "set_wheels");
  if (std::isnan(left) || std::isnan(right))
    throw std::invalid_argument("box2d world: set_wheels: NaN speed for robot '" + r.name + "'");
  RobotState& st = robots_[robot].state;
  st.left_speed = std::clamp(left, -kMaxWheelSpeed, kMaxWheelSpeed);
  st.right_speed = std::clamp(right, -kMaxWheelSpeed, kMaxWheelSpeed);
}

IrReadings Box2DWorld::ir(std::size_t robot) const { return robot_at(robot, "ir").ir; }

RobotState Box2DWorld::state(std::size_t robot) const { return robot_at(robot, "state").state; }

}  // namespace symb::sim
