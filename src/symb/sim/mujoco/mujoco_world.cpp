#include "symb/sim/mujoco/mujoco_world.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <mujoco/mujoco.h>

namespace symb::sim::mujoco {

namespace {

// A ray that meets its own module goes on from just past the hit (m).
constexpr double kRayStepPast = 1e-6;

// MuJoCo reports warnings only through one process-wide function pointer; by default it prints
// them and appends them to MUJOCO_LOG.TXT in the working folder. The world reads the same warnings
// from its own mjData's counters and returns them as errors, so the printing is switched off,
// once, and only when nobody else has installed a handler.
void quiet_mujoco_warnings() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (mju_user_warning == nullptr) mju_user_warning = [](const char*) {};
  });
}

// Row `index` of a MuJoCo array of `width` numbers a row (xpos is nbody x 3, xmat nbody x 9, ...).
template <class T>
T* row(T* array, int width, int index) {
  return array + static_cast<std::ptrdiff_t>(width) * index;
}

Vec3 rotate(const mjtNum* mat, const Vec3& v) {
  Vec3 out;
  mju_rotVecMat(out.data(), v.data(), mat);
  return out;
}

double distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

double opposed_angle(const Vec3& na, const Vec3& nb) {
  const double dot = -(na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2]);
  return std::acos(std::clamp(dot, -1.0, 1.0));
}

std::string mm(double metres) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << metres * 1000 << " mm";
  return out.str();
}

std::string deg(double radians) {
  std::ostringstream out;
  out.precision(3);
  out << std::fixed << radians * 180 / std::numbers::pi << " deg";
  return out.str();
}

// The warnings that mean the run can no longer be trusted.
constexpr std::array<std::pair<int, const char*>, 5> kFatalWarnings = {{
    {mjWARN_BADQPOS, "a bad number in the positions (qpos)"},
    {mjWARN_BADQVEL, "a bad number in the speeds (qvel)"},
    {mjWARN_BADQACC, "a bad number in the accelerations (qacc): the simulation diverged"},
    {mjWARN_CNSTRFULL, "more constraint rows than njmax reserves"},
    {mjWARN_CONTACTFULL, "more contacts than nconmax reserves"},
}};

}  // namespace

// Outside the anonymous namespace: MujocoWorld::State, which has external linkage, holds one.
struct DataDeleter {
  void operator()(mjData* data) const { mj_deleteData(data); }
};

const char* state_name(ConnectorState state) {
  switch (state) {
    case ConnectorState::kFree: return "free";
    case ConnectorState::kAligned: return "aligned";
    case ConnectorState::kDocked: return "docked";
  }
  return "?";
}

const char* change_name(DockChange change) {
  switch (change) {
    case DockChange::kLatched: return "latched";
    case DockChange::kUnlatched: return "unlatched";
    case DockChange::kRefused: return "refused";
  }
  return "?";
}

double Pose3::yaw() const {
  const auto& q = quaternion;
  return std::atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] * q[2] + q[3] * q[3]));
}

struct MujocoWorld::State {
  struct Connector {
    int body = -1;  // the module's base or tail
    bool open = true;
    std::size_t weld = kNoIndex;  // the weld holding it, when docked
    std::size_t other_module = kNoIndex;
    std::size_t other_connector = kNoIndex;
  };
  struct Module {
    int base = -1, tail = -1;
    int free_qpos = -1, free_dof = -1;
    int hinge_qpos = -1, hinge_dof = -1, hinge_actuator = -1;
    int wheel_actuator[2] = {-1, -1};
    int base_geom = -1, tail_geom = -1;  // the two box halves, where touch is felt
    std::vector<Connector> connectors;
  };
  // What a ray met: the distance along it (m) and the object's id; nothing is {-1, kNothingId}.
  struct Hit {
    double distance = -1;
    int object = kNothingId;
  };
  struct Weld {
    int equality = -1;
    bool in_use = false;
  };

  std::vector<ModuleSpec> specs;
  std::string mjcf;
  ModelPtr model;
  std::unique_ptr<mjData, DataDeleter> data;
  std::vector<Module> modules;
  std::vector<std::size_t> body_module;  // per MuJoCo body: its module, or kNoIndex
  std::vector<int> geom_object;          // per MuJoCo geom: its object id (see the header)
  std::size_t obstacles = 0;
  // The IMU: each module's base speed (world frame, m/s) at the end of the last step() call and
  // at its start, and how long that call stepped (s).
  std::vector<Vec3> speed_now, speed_before;
  double imu_span = 0;
  std::vector<Weld> welds;
  std::vector<DockEvent> log;
  std::uint64_t steps = 0;
  std::string failure;

  const Module& at(std::size_t module) const {
    if (module >= modules.size())
      throw std::out_of_range("module " + std::to_string(module) + " (the world has " + std::to_string(modules.size()) +
                              ")");
    return modules[module];
  }
  const Connector& at(std::size_t module, std::size_t connector) const {
    const Module& m = at(module);
    if (connector >= m.connectors.size())
      throw std::out_of_range("connector " + std::to_string(connector) + " of module '" + specs[module].name +
                              "' (it has " + std::to_string(m.connectors.size()) + ")");
    return m.connectors[connector];
  }
  Connector& at(std::size_t module, std::size_t connector) {
    return const_cast<Connector&>(static_cast<const State*>(this)->at(module, connector));
  }
  std::string label(std::size_t module, std::size_t connector) const {
    return specs[module].name + "." + specs[module].kind.connectors[connector].name;
  }
  // Bodies' poses for the current qpos: mj_step leaves them one step behind its new qpos. Only
  // derived quantities change, so the next step's result is the same with or without it.
  void refresh() { mj_kinematics(model.get(), data.get()); }

  // The base's linear speed: a free joint's first three speeds are its origin's, world frame.
  Vec3 base_speed(std::size_t module) const {
    const mjtNum* v = data->qvel + modules[module].free_dof;
    return {v[0], v[1], v[2]};
  }

  // The first thing along the ray from `origin` (unit `direction`) within `range` that is not
  // `module`'s own. MuJoCo's ray skips one body; the first pass skips `body` (the one the sensor
  // sits on), and each of the module's other geoms met is stepped past, at most once per geom.
  Hit cast(std::size_t module, int body, Vec3 origin, const Vec3& direction, double range) const {
    double travelled = 0;
    for (int pass = 0; pass <= model->ngeom; ++pass) {
      int geom = -1;
      const double hit =
          mj_ray(model.get(), data.get(), origin.data(), direction.data(), nullptr, 1, pass == 0 ? body : -1, &geom);
      if (hit < 0 || geom < 0 || travelled + hit > range) return {};
      const int hit_body = model->geom_bodyid[geom];
      if (body_module[static_cast<std::size_t>(hit_body)] != module)
        return {travelled + hit, geom_object[static_cast<std::size_t>(geom)]};
      const double skip = hit + kRayStepPast;
      for (int i = 0; i < 3; ++i) origin[static_cast<std::size_t>(i)] += skip * direction[static_cast<std::size_t>(i)];
      travelled += skip;
    }
    return {};
  }

  // The geoms a fan of rays from `origin` may meet within `range`: every plane, and every other
  // geom not of `module` whose bounding sphere reaches within range (and, for a camera, which
  // narrower than 180 degrees sees only ahead, not wholly behind the plane through `origin`
  // across `out`). A camera's 768 rays then test a handful of geoms instead of the whole world.
  void candidates(std::size_t module, const Vec3& origin, const Vec3* out, double range,
                  std::vector<int>& geoms) const {
    geoms.clear();
    for (int g = 0; g < model->ngeom; ++g) {
      if (body_module[static_cast<std::size_t>(model->geom_bodyid[g])] == module) continue;
      if (model->geom_type[g] == mjGEOM_PLANE) {
        geoms.push_back(g);
        continue;
      }
      const mjtNum* p = row(data->geom_xpos, 3, g);
      const Vec3 rel = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
      const double bound = model->geom_rbound[g];
      if (std::hypot(rel[0], rel[1], rel[2]) - bound > range) continue;
      if (out != nullptr && rel[0] * (*out)[0] + rel[1] * (*out)[1] + rel[2] * (*out)[2] < -bound) continue;
      geoms.push_back(g);
    }
  }

  // The nearest of `geoms` along the ray (unit `direction`) within `range`, by MuJoCo's own
  // ray-geom intersections, each behind a bounding-sphere test as in mj_ray.
  Hit cast_among(const std::vector<int>& geoms, const Vec3& origin, const Vec3& direction, double range) const {
    Hit best;
    for (const int g : geoms) {
      const mjtNum* p = row(data->geom_xpos, 3, g);
      if (model->geom_type[g] != mjGEOM_PLANE) {
        const Vec3 rel = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
        const double along = rel[0] * direction[0] + rel[1] * direction[1] + rel[2] * direction[2];
        const double bound = model->geom_rbound[g];
        if (along + bound < 0) continue;
        if (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2] - along * along > bound * bound) continue;
      }
      const double hit = mju_rayGeom(p, row(data->geom_xmat, 9, g), row(model->geom_size, 3, g), origin.data(),
                                     direction.data(), model->geom_type[g]);
      if (hit >= 0 && hit <= range && (best.distance < 0 || hit < best.distance))
        best = {hit, geom_object[static_cast<std::size_t>(g)]};
    }
    return best;
  }

  // A sensor's mount on a face: the body it sits on (the tail when behind the hinge), its origin
  // and its frame's out (the face's normal), left and up axes, in the world frame.
  struct Mount {
    int body;
    Vec3 origin, out, left, up;
  };
  Mount mount(std::size_t module, Face face, const Vec3& position) const {
    const Module& mod = at(module);
    const int body = position[0] < 0 ? mod.tail : mod.base;
    const mjtNum* mat = row(data->xmat, 9, body);
    const Vec3 n = face_normal(face);
    return {body, point(body, position), rotate(mat, n), rotate(mat, {-n[1], n[0], 0}), rotate(mat, {0, 0, 1})};
  }

  Vec3 point(int body, const Vec3& local) const {
    Vec3 p = rotate(row(data->xmat, 9, body), local);
    for (int i = 0; i < 3; ++i) p[i] += row(data->xpos, 3, body)[i];
    return p;
  }
  Vec3 position(std::size_t module, std::size_t connector) const {
    return point(at(module, connector).body, specs[module].kind.connectors[connector].position);
  }
  Vec3 normal(std::size_t module, std::size_t connector) const {
    return rotate(row(data->xmat, 9, at(module, connector).body),
                  face_normal(specs[module].kind.connectors[connector].face));
  }
  // A log entry for `module`'s connector now, with the partner's distance and angle when there is one.
  DockEvent event_between(std::size_t module, std::size_t connector, std::size_t other_module,
                          std::size_t other_connector) const {
    DockEvent event;
    event.step = steps;
    event.time = static_cast<double>(steps) * kTimestep;
    event.module = module;
    event.connector = connector;
    if (other_module == kNoIndex) return event;
    event.other_module = other_module;
    event.other_connector = other_connector;
    event.distance = distance(position(module, connector), position(other_module, other_connector));
    event.angle = opposed_angle(normal(module, connector), normal(other_module, other_connector));
    return event;
  }
  // The other modules' connector nearest to this one (lowest indices on a tie).
  std::optional<std::pair<std::size_t, std::size_t>> nearest(std::size_t module, std::size_t connector) const {
    const Vec3 p = position(module, connector);
    std::optional<std::pair<std::size_t, std::size_t>> best;
    double best_distance = 0;
    for (std::size_t m = 0; m < modules.size(); ++m) {
      if (m == module) continue;
      for (std::size_t c = 0; c < modules[m].connectors.size(); ++c) {
        const double dd = distance(p, position(m, c));
        if (!best || dd < best_distance) {
          best = {m, c};
          best_distance = dd;
        }
      }
    }
    return best;
  }
};

MujocoWorld::MujocoWorld(std::unique_ptr<State> state) : s_(std::move(state)) {}
MujocoWorld::MujocoWorld(MujocoWorld&&) noexcept = default;
MujocoWorld& MujocoWorld::operator=(MujocoWorld&&) noexcept = default;
MujocoWorld::~MujocoWorld() = default;

kernel::Result<MujocoWorld> MujocoWorld::make(std::vector<ModuleSpec> modules, ModelOptions options) {
  quiet_mujoco_warnings();
  auto text = mjcf_text(modules, options);
  if (!text) return kernel::Error{text.error()};
  auto model = load_mjcf(*text);
  if (!model) return kernel::Error{model.error()};
  auto s = std::make_unique<State>();
  s->specs = std::move(modules);
  s->mjcf = std::move(text).value();
  s->model = std::move(model).value();
  const mjModel* m = s->model.get();
  s->data.reset(mj_makeData(m));
  if (!s->data) return kernel::Error{"MuJoCo could not allocate the model's data (nstack too large?)"};

  auto id = [&](int type, const std::string& name) -> int { return mj_name2id(m, type, name.c_str()); };
  s->body_module.assign(static_cast<std::size_t>(m->nbody), kNoIndex);
  for (std::size_t i = 0; i < s->specs.size(); ++i) {
    const ModuleSpec& spec = s->specs[i];
    const std::string& n = spec.name;
    State::Module mod;
    mod.base = id(mjOBJ_BODY, n + ".base");
    mod.tail = id(mjOBJ_BODY, n + ".tail");
    const int free = id(mjOBJ_JOINT, n + ".free");
    mod.free_qpos = m->jnt_qposadr[free];
    mod.free_dof = m->jnt_dofadr[free];
    const int hinge = id(mjOBJ_JOINT, n + ".hinge");
    mod.hinge_qpos = m->jnt_qposadr[hinge];
    mod.hinge_dof = m->jnt_dofadr[hinge];
    mod.hinge_actuator = id(mjOBJ_ACTUATOR, n + ".hinge");
    mod.base_geom = id(mjOBJ_GEOM, n + ".base");
    mod.tail_geom = id(mjOBJ_GEOM, n + ".tail");
    s->body_module[static_cast<std::size_t>(mod.base)] = i;
    s->body_module[static_cast<std::size_t>(mod.tail)] = i;
    if (spec.kind.has_wheels) {
      mod.wheel_actuator[0] = id(mjOBJ_ACTUATOR, n + ".wheel_l");
      mod.wheel_actuator[1] = id(mjOBJ_ACTUATOR, n + ".wheel_r");
      s->body_module[static_cast<std::size_t>(id(mjOBJ_BODY, n + ".wheel_l"))] = i;
      s->body_module[static_cast<std::size_t>(id(mjOBJ_BODY, n + ".wheel_r"))] = i;
    }
    for (const auto& c : spec.kind.connectors) {
      State::Connector con;
      con.body = c.position[0] < 0 ? mod.tail : mod.base;
      mod.connectors.push_back(con);
    }
    s->modules.push_back(std::move(mod));
  }
  for (std::size_t k = 0; k < options.spare_welds; ++k)
    s->welds.push_back({id(mjOBJ_EQUALITY, "spare_weld_" + std::to_string(k)), false});
  s->geom_object.assign(static_cast<std::size_t>(m->ngeom), kNothingId);
  for (int g = 0; g < m->ngeom; ++g) {
    const std::size_t owner = s->body_module[static_cast<std::size_t>(m->geom_bodyid[g])];
    if (owner != kNoIndex) s->geom_object[static_cast<std::size_t>(g)] = module_object_id(owner);
  }
  s->obstacles = options.obstacles.size();
  for (std::size_t k = 0; k < s->obstacles; ++k)
    s->geom_object[static_cast<std::size_t>(id(mjOBJ_GEOM, "obstacle_" + std::to_string(k)))] = obstacle_object_id(k);
  mj_forward(m, s->data.get());
  for (std::size_t i = 0; i < s->modules.size(); ++i) s->speed_now.push_back(s->base_speed(i));
  s->speed_before = s->speed_now;
  return MujocoWorld(std::move(s));
}

const std::string& MujocoWorld::mjcf() const { return s_->mjcf; }
std::size_t MujocoWorld::module_count() const { return s_->modules.size(); }
std::size_t MujocoWorld::degrees_of_freedom() const { return static_cast<std::size_t>(s_->model->nv); }
const ModuleSpec& MujocoWorld::module(std::size_t module) const {
  s_->at(module);
  return s_->specs[module];
}

std::optional<std::size_t> MujocoWorld::find_module(std::string_view name) const {
  for (std::size_t i = 0; i < s_->specs.size(); ++i)
    if (s_->specs[i].name == name) return i;
  return std::nullopt;
}

std::optional<std::size_t> MujocoWorld::find_connector(std::size_t module, std::string_view name) const {
  const auto& connectors = this->module(module).kind.connectors;
  for (std::size_t i = 0; i < connectors.size(); ++i)
    if (connectors[i].name == name) return i;
  return std::nullopt;
}

kernel::Status MujocoWorld::step(std::uint64_t substeps) {
  if (!s_->failure.empty()) return kernel::Error{"the world has failed and does not step: " + s_->failure};
  const mjModel* m = s_->model.get();
  mjData* d = s_->data.get();
  s_->speed_before.swap(s_->speed_now);
  s_->imu_span = static_cast<double>(substeps) * kTimestep;
  for (std::uint64_t i = 0; i < substeps; ++i) {
    std::array<int, kFatalWarnings.size()> before{};
    for (std::size_t w = 0; w < kFatalWarnings.size(); ++w) before[w] = d->warning[kFatalWarnings[w].first].number;
    mj_step(m, d);
    ++s_->steps;
    for (std::size_t w = 0; w < kFatalWarnings.size(); ++w) {
      const auto& warning = d->warning[kFatalWarnings[w].first];
      if (warning.number == before[w]) continue;
      std::ostringstream why;
      why << "step " << s_->steps << " (t = " << time() << " s): " << kFatalWarnings[w].second << " (MuJoCo's index "
          << warning.lastinfo << ")";
      s_->failure = why.str();
      return kernel::Error{s_->failure};
    }
  }
  s_->refresh();
  for (std::size_t i = 0; i < s_->modules.size(); ++i) s_->speed_now[i] = s_->base_speed(i);
  return {};
}

std::uint64_t MujocoWorld::steps() const { return s_->steps; }
double MujocoWorld::time() const { return static_cast<double>(s_->steps) * kTimestep; }
bool MujocoWorld::failed() const { return !s_->failure.empty(); }

kernel::Status MujocoWorld::set_wheels(std::size_t module, double left, double right) {
  const auto& mod = s_->at(module);
  const ModuleKind& kind = s_->specs[module].kind;
  if (!kind.has_wheels)
    return kernel::Error{"module '" + s_->specs[module].name + "' (kind '" + kind.name + "') has no wheels"};
  const double limit = kind.wheels.max_speed;
  const double speeds[2] = {left, right};
  for (int w = 0; w < 2; ++w)
    s_->data->ctrl[mod.wheel_actuator[w]] = std::clamp(speeds[w], -limit, limit) / kind.wheels.radius;
  return {};
}

void MujocoWorld::set_hinge_target(std::size_t module, double angle) {
  const auto& mod = s_->at(module);
  const auto& range = s_->specs[module].kind.hinge.range;
  s_->data->ctrl[mod.hinge_actuator] = std::clamp(angle, range[0], range[1]);
}

double MujocoWorld::hinge_angle(std::size_t module) const { return s_->data->qpos[s_->at(module).hinge_qpos]; }
double MujocoWorld::hinge_speed(std::size_t module) const { return s_->data->qvel[s_->at(module).hinge_dof]; }

Pose3 MujocoWorld::pose(std::size_t module) const {
  const int body = s_->at(module).base;
  Pose3 pose;
  for (int i = 0; i < 3; ++i) pose.position[static_cast<std::size_t>(i)] = row(s_->data->xpos, 3, body)[i];
  for (int i = 0; i < 4; ++i) pose.quaternion[static_cast<std::size_t>(i)] = row(s_->data->xquat, 4, body)[i];
  return pose;
}

kernel::Status MujocoWorld::place(std::size_t module, const StartPose& where) {
  const auto& mod = s_->at(module);
  for (std::size_t c = 0; c < mod.connectors.size(); ++c)
    if (mod.connectors[c].weld != kNoIndex)
      return kernel::Error{"place " + s_->specs[module].name + " refused: " + s_->label(module, c) + " is docked"};
  mjtNum* q = s_->data->qpos + mod.free_qpos;
  q[0] = where.x;
  q[1] = where.y;
  q[2] = rest_height(s_->specs[module].kind);
  q[3] = std::cos(where.yaw / 2);
  q[4] = 0;
  q[5] = 0;
  q[6] = std::sin(where.yaw / 2);
  std::fill_n(s_->data->qvel + mod.free_dof, 6, 0.0);
  s_->speed_now[module] = s_->speed_before[module] = Vec3{};
  s_->refresh();
  return {};
}

std::optional<double> MujocoWorld::ir(std::size_t module, Face face) const {
  s_->at(module);
  const ModuleKind& kind = s_->specs[module].kind;
  const auto sensor = std::find_if(kind.ir.begin(), kind.ir.end(), [&](const IrSpec& ir) { return ir.face == face; });
  if (sensor == kind.ir.end()) return std::nullopt;
  const State::Mount at = s_->mount(module, face, sensor->position);
  const State::Hit hit = s_->cast(module, at.body, at.origin, at.out, sensor->range);
  if (hit.distance < 0) return std::nullopt;
  return hit.distance;
}

ImuReading MujocoWorld::imu(std::size_t module) const {
  const auto& mod = s_->at(module);
  const mjtNum* mat = row(s_->data->xmat, 9, mod.base);
  Vec3 specific{};
  for (std::size_t i = 0; i < 3; ++i) {
    const double acceleration =
        s_->imu_span > 0 ? (s_->speed_now[module][i] - s_->speed_before[module][i]) / s_->imu_span : 0.0;
    specific[i] = acceleration - s_->model->opt.gravity[i];
  }
  ImuReading r;
  mju_rotVecMatT(r.acceleration.data(), specific.data(), mat);
  // A free joint's last three speeds are the body's angular velocity in its own frame.
  const mjtNum* w = s_->data->qvel + mod.free_dof + 3;
  r.angular_velocity = {w[0], w[1], w[2]};
  return r;
}

std::array<double, 4> MujocoWorld::touch(std::size_t module) const {
  const auto& mod = s_->at(module);
  const mjModel* m = s_->model.get();
  const mjData* d = s_->data.get();
  std::array<double, 4> force{};
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    // The contact normal points from geom1 to geom2: out of geom1, into geom2.
    double sign = 0;
    int geom = -1;
    if (c.geom1 == mod.base_geom || c.geom1 == mod.tail_geom) {
      sign = 1;
      geom = c.geom1;
    } else if (c.geom2 == mod.base_geom || c.geom2 == mod.tail_geom) {
      sign = -1;
      geom = c.geom2;
    } else {
      continue;
    }
    const Vec3 outward = {sign * c.frame[0], sign * c.frame[1], sign * c.frame[2]};
    Vec3 local;
    mju_rotVecMatT(local.data(), outward.data(), row(d->xmat, 9, m->geom_bodyid[geom]));
    const double ax = std::abs(local[0]), ay = std::abs(local[1]);
    if (std::abs(local[2]) >= std::max(ax, ay)) continue;
    const Face face =
        ax >= ay ? (local[0] > 0 ? Face::kFront : Face::kBack) : (local[1] > 0 ? Face::kLeft : Face::kRight);
    mjtNum wrench[6];
    mj_contactForce(m, d, i, wrench);
    force[static_cast<std::size_t>(face)] += std::abs(wrench[0]);
  }
  return force;
}

void MujocoWorld::laser(std::size_t module, std::span<float> distances) const {
  s_->at(module);
  const ModuleKind& kind = s_->specs[module].kind;
  if (!kind.laser) throw std::invalid_argument("module '" + s_->specs[module].name + "' has no laser");
  const LaserSpec& l = *kind.laser;
  if (distances.size() != l.rays)
    throw std::invalid_argument("laser of module '" + s_->specs[module].name + "' has " + std::to_string(l.rays) +
                                " rays, not " + std::to_string(distances.size()));
  const State::Mount at = s_->mount(module, l.face, l.position);
  std::vector<int> geoms;
  s_->candidates(module, at.origin, nullptr, l.range, geoms);
  for (std::size_t r = 0; r < l.rays; ++r) {
    const double angle =
        l.rays == 1 ? 0.0
                    : -l.field_of_view / 2 + l.field_of_view * static_cast<double>(r) / static_cast<double>(l.rays - 1);
    const double c = std::cos(angle), sn = std::sin(angle);
    const Vec3 dir = {c * at.out[0] + sn * at.left[0], c * at.out[1] + sn * at.left[1],
                      c * at.out[2] + sn * at.left[2]};
    const State::Hit hit = s_->cast_among(geoms, at.origin, dir, l.range);
    distances[r] = static_cast<float>(hit.distance < 0 ? l.range : hit.distance);
  }
}

void MujocoWorld::camera(std::size_t module, std::span<float> depth, std::span<std::int32_t> ids) const {
  s_->at(module);
  const ModuleKind& kind = s_->specs[module].kind;
  if (!kind.camera) throw std::invalid_argument("module '" + s_->specs[module].name + "' has no camera");
  const CameraSpec& cam = *kind.camera;
  const std::size_t pixels = cam.width * cam.height;
  if (depth.size() != pixels || ids.size() != pixels)
    throw std::invalid_argument("camera of module '" + s_->specs[module].name + "' has " + std::to_string(pixels) +
                                " pixels");
  const State::Mount at = s_->mount(module, cam.face, cam.position);
  const double w = static_cast<double>(cam.width), h = static_cast<double>(cam.height);
  const double focal = (w / 2) / std::tan(cam.field_of_view / 2);
  std::vector<int> geoms;
  s_->candidates(module, at.origin, &at.out, cam.range, geoms);
  for (std::size_t v = 0; v < cam.height; ++v) {
    const double up = h / 2 - static_cast<double>(v) - 0.5;
    for (std::size_t u = 0; u < cam.width; ++u) {
      const double left = w / 2 - static_cast<double>(u) - 0.5;
      Vec3 dir;
      for (std::size_t i = 0; i < 3; ++i) dir[i] = focal * at.out[i] + left * at.left[i] + up * at.up[i];
      const double norm = std::hypot(dir[0], dir[1], dir[2]);
      for (double& x : dir) x /= norm;
      const State::Hit hit = s_->cast_among(geoms, at.origin, dir, cam.range);
      const std::size_t p = v * cam.width + u;
      depth[p] = static_cast<float>(hit.distance < 0 ? cam.range : hit.distance);
      ids[p] = hit.distance < 0 ? kNothingId : hit.object;
    }
  }
}

std::size_t MujocoWorld::obstacle_count() const { return s_->obstacles; }

Vec3 MujocoWorld::connector_position(std::size_t module, std::size_t connector) const {
  return s_->position(module, connector);
}
Vec3 MujocoWorld::connector_normal(std::size_t module, std::size_t connector) const {
  return s_->normal(module, connector);
}
void MujocoWorld::set_open(std::size_t module, std::size_t connector, bool open) {
  s_->at(module, connector).open = open;
}
bool MujocoWorld::is_open(std::size_t module, std::size_t connector) const { return s_->at(module, connector).open; }

ConnectorState MujocoWorld::connector_state(std::size_t module, std::size_t connector) const {
  if (s_->at(module, connector).weld != kNoIndex) return ConnectorState::kDocked;
  const auto other = s_->nearest(module, connector);
  if (!other || s_->at(other->first, other->second).weld != kNoIndex) return ConnectorState::kFree;
  const DockEvent e = s_->event_between(module, connector, other->first, other->second);
  return e.distance <= kLatchPositionTolerance && e.angle <= kLatchAngleTolerance ? ConnectorState::kAligned
                                                                                  : ConnectorState::kFree;
}

std::optional<Beacon> MujocoWorld::beacon(std::size_t module, std::size_t connector) const {
  const auto wrap = [](double a) { return std::remainder(a, 2 * std::numbers::pi); };
  const auto opposite = [](Face f) {
    switch (f) {
      case Face::kFront: return Face::kBack;
      case Face::kBack: return Face::kFront;
      case Face::kLeft: return Face::kRight;
      case Face::kRight: return Face::kLeft;
    }
    return Face::kBack;
  };
  s_->at(module, connector);  // range-checks both handles
  const Face wanted = opposite(s_->specs[module].kind.connectors.at(connector).face);
  const Vec3 ps = s_->position(module, connector), ns = s_->normal(module, connector);
  const double phi = std::atan2(ns[1], ns[0]);
  std::optional<Beacon> best;
  for (std::size_t m = 0; m < s_->specs.size(); ++m) {
    if (m == module) continue;
    const auto& cs = s_->specs[m].kind.connectors;
    for (std::size_t c = 0; c < cs.size(); ++c) {
      if (cs[c].face != wanted) continue;
      const auto& st = s_->at(m, c);
      if (!st.open || st.weld != kNoIndex) continue;
      const Vec3 pt = s_->position(m, c), nt = s_->normal(m, c);
      const double dx = pt[0] - ps[0], dy = pt[1] - ps[1], d = std::hypot(dx, dy);
      if (d > kBeaconRange || (best && d >= best->distance)) continue;
      const double bearing = d > 0 ? wrap(std::atan2(dy, dx) - phi) : 0.0;
      // The cosine of my place off the target's normal, seen from the target.
      const double off = d > 0 ? -(dx * nt[0] + dy * nt[1]) / d : 1.0;
      if (std::abs(bearing) > kBeaconCone || off < std::cos(kBeaconFaceCone)) continue;
      best = Beacon{d, bearing, wrap(std::atan2(-nt[1], -nt[0]) - phi), m, c};
    }
  }
  return best;
}

std::optional<std::pair<std::size_t, std::size_t>> MujocoWorld::docked_to(std::size_t module,
                                                                          std::size_t connector) const {
  const auto& c = s_->at(module, connector);
  if (c.weld == kNoIndex) return std::nullopt;
  return std::pair{c.other_module, c.other_connector};
}

kernel::Status MujocoWorld::latch(std::size_t module, std::size_t connector) {
  State& s = *s_;
  auto& self = s.at(module, connector);
  DockEvent event = s.event_between(module, connector, kNoIndex, kNoIndex);
  auto refuse = [&](const std::string& why) -> kernel::Status {
    event.change = DockChange::kRefused;
    event.reason = why;
    s.log.push_back(event);
    return kernel::Error{"latch " + s.label(module, connector) + " refused: " + why};
  };
  if (!s.failure.empty()) return refuse("the world has failed");
  if (self.weld != kNoIndex)
    return refuse("it is already docked to " + s.label(self.other_module, self.other_connector));
  if (!self.open) return refuse("it is closed");
  const auto other = s.nearest(module, connector);
  if (!other) return refuse("there is no other module");
  const auto [om, oc] = *other;
  auto& partner = s.at(om, oc);
  event = s.event_between(module, connector, om, oc);
  const Vec3 pa = s.position(module, connector), pb = s.position(om, oc);
  const std::string partner_label = s.label(om, oc);
  if (partner.weld != kNoIndex)
    return refuse("the nearest connector, " + partner_label + ", is already docked to " +
                  s.label(partner.other_module, partner.other_connector));
  if (!partner.open) return refuse("the nearest connector, " + partner_label + ", is closed");
  if (event.distance > kLatchPositionTolerance)
    return refuse("position: " + partner_label + " is " + mm(event.distance) + " away, " +
                  mm(event.distance - kLatchPositionTolerance) + " beyond the tolerance of " +
                  mm(kLatchPositionTolerance));
  if (event.angle > kLatchAngleTolerance)
    return refuse("angle: " + partner_label + " faces it " + deg(event.angle) + " off, " +
                  deg(event.angle - kLatchAngleTolerance) + " beyond the tolerance of " + deg(kLatchAngleTolerance));
  const auto weld = std::find_if(s.welds.begin(), s.welds.end(), [](const State::Weld& w) { return !w.in_use; });
  if (weld == s.welds.end()) return refuse("all " + std::to_string(s.welds.size()) + " spare welds are in use");

  // Retarget the weld (MuJoCo 2.2.2 eq_data: [0:3] the anchor in body 2's frame, [3:6] the same
  // point in body 1's frame, [6:10] the relative orientation neg(q1) * q2, [10] torque scale) to
  // hold the pose the bodies have now, anchored midway between the connectors.
  mjModel* m = s.model.get();
  const mjData* d = s.data.get();
  const int b1 = self.body, b2 = partner.body;
  const int eq = weld->equality;
  m->eq_obj1id[eq] = b1;
  m->eq_obj2id[eq] = b2;
  mjtNum* data = row(m->eq_data, mjNEQDATA, eq);
  mjtNum anchor[3], offset[3];
  for (int i = 0; i < 3; ++i) anchor[i] = (pa[static_cast<std::size_t>(i)] + pb[static_cast<std::size_t>(i)]) / 2;
  for (int i = 0; i < 3; ++i) offset[i] = anchor[i] - row(d->xpos, 3, b2)[i];
  mju_rotVecMatT(data, offset, row(d->xmat, 9, b2));
  for (int i = 0; i < 3; ++i) offset[i] = anchor[i] - row(d->xpos, 3, b1)[i];
  mju_rotVecMatT(data + 3, offset, row(d->xmat, 9, b1));
  mjtNum inverse[4];
  mju_negQuat(inverse, row(d->xquat, 4, b1));
  mju_mulQuat(data + 6, inverse, row(d->xquat, 4, b2));
  data[10] = 1;
  m->eq_active[eq] = 1;
  weld->in_use = true;
  const std::size_t weld_index = static_cast<std::size_t>(weld - s.welds.begin());
  self.weld = partner.weld = weld_index;
  self.other_module = om;
  self.other_connector = oc;
  partner.other_module = module;
  partner.other_connector = connector;
  event.change = DockChange::kLatched;
  event.reason = "weld " + std::to_string(weld_index);
  s.log.push_back(event);
  return {};
}

kernel::Status MujocoWorld::unlatch(std::size_t module, std::size_t connector) {
  State& s = *s_;
  auto& self = s.at(module, connector);
  DockEvent event = s.event_between(module, connector, self.other_module, self.other_connector);
  if (self.weld == kNoIndex) {
    event.change = DockChange::kRefused;
    event.reason = "it is not docked";
    s.log.push_back(event);
    return kernel::Error{"unlatch " + s.label(module, connector) + " refused: it is not docked"};
  }
  const std::size_t weld = self.weld;
  auto& partner = s.at(self.other_module, self.other_connector);
  s.model->eq_active[s.welds[weld].equality] = 0;
  s.welds[weld].in_use = false;
  for (auto* c : {&self, &partner}) {
    c->weld = kNoIndex;
    c->other_module = kNoIndex;
    c->other_connector = kNoIndex;
  }
  event.change = DockChange::kUnlatched;
  event.reason = "weld " + std::to_string(weld);
  s.log.push_back(event);
  return {};
}

const std::vector<DockEvent>& MujocoWorld::docking_log() const { return s_->log; }

std::size_t MujocoWorld::spare_welds_free() const {
  return static_cast<std::size_t>(
      std::count_if(s_->welds.begin(), s_->welds.end(), [](const State::Weld& w) { return !w.in_use; }));
}

std::size_t MujocoWorld::stack_reserved() const { return static_cast<std::size_t>(s_->model->nstack); }
std::size_t MujocoWorld::stack_peak() const { return static_cast<std::size_t>(s_->data->maxuse_stack); }

}  // namespace symb::sim::mujoco
