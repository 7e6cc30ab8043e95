

#include "symb/apps/run/steps_h5.hpp"

#include <hdf5.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace symb::apps::run {

// An HDF5 identifier closed by its own close function when it goes (named, not file-local: a
// member of StepsH5::Handles).
class StepsH5Id {
 public:
  StepsH5Id() = default;
  StepsH5Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  StepsH5Id(StepsH5Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  StepsH5Id& operator=(StepsH5Id&& o) noexcept {
    reset();
    id_ = std::exchange(o.id_, H5I_INVALID_HID);
    close_ = o.close_;
    return *this;
  }
  ~StepsH5Id() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  herr_t reset() {
    herr_t r = 0;
    if (id_ >= 0 && close_) r = close_(id_);
    id_ = H5I_INVALID_HID;
    return r;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

namespace {

// A chunk is (block steps) x (up to kChunkRobots robots) x (the last axis): one robot's history
// reads a slice of the file, not all of it, and a block of steps in memory stays a few MB.
constexpr hsize_t kChunkRobots = 128;
constexpr std::size_t kBlockBytes = 4u << 20;  // the block in memory, at most about this
constexpr std::uint32_t kMinBlock = 8, kMaxBlock = 256;
// Per robot and step: pose 24, ir 28, wheels 16, contact 1 bytes.
constexpr std::size_t kBytesPerRobotStep = 3 * 8 + sim::kIrCount * 4 + 2 * 8 + 1;
// Measured on 1,000 robots' steps (docs/run.md): level 1 takes about 1.1 ms of CPU per step,
// level 4 15 % more for 3 % less size, level 6 twice level 1's time for 5 % less.
constexpr unsigned kDeflateLevel = 1;
// The IR readings are noisy floats that deflate barely shrinks: rounded to 0.1 as steps.csv
// rounds them (half to even, as printf; the nearest float to the CSV's text), 7.7 MB per 200 steps of 1,000 robots
// become 6.4. (HDF5's scale-offset filter shrinks them further but is off by up to a whole 0.1.)
constexpr double kIrScale = 10;

StepsH5Id string_type() {
  StepsH5Id t(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(t.get(), H5T_VARIABLE);
  H5Tset_cset(t.get(), H5T_CSET_UTF8);
  return t;
}

bool set_string_attribute(hid_t where, const char* name, const std::string& value) {
  StepsH5Id type = string_type();
  StepsH5Id space(H5Screate(H5S_SCALAR), H5Sclose);
  StepsH5Id attr(H5Acreate2(where, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const char* text = value.c_str();
  return attr.valid() && H5Awrite(attr.get(), type.get(), &text) >= 0;
}

template <class T>
bool set_number_attribute(hid_t where, const char* name, hid_t type, T value) {
  StepsH5Id space(H5Screate(H5S_SCALAR), H5Sclose);
  // Written again on close (steps, simulated_s): replace rather than fail.
  if (H5Aexists(where, name) > 0) H5Adelete(where, name);
  StepsH5Id attr(H5Acreate2(where, name, type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  return attr.valid() && H5Awrite(attr.get(), type, &value) >= 0;
}

}  // namespace

struct StepsH5::Handles {
  StepsH5Id file, step, time, pose, ir, wheels, contact;
};

namespace {

// An empty array of `rank` axes, extensible along the first, chunked as `chunk`, shuffled and
// deflated; `columns` names the last axis (an attribute).
StepsH5Id make_array(hid_t file, const char* name, hid_t type, std::span<const hsize_t> inner,
                     std::span<const hsize_t> chunk, const char* columns) {
  std::array<hsize_t, 3> dims{}, maxdims{};
  const int rank = static_cast<int>(inner.size()) + 1;
  dims[0] = 0;
  maxdims[0] = H5S_UNLIMITED;
  for (std::size_t i = 0; i < inner.size(); ++i) dims[i + 1] = maxdims[i + 1] = inner[i];
  StepsH5Id space(H5Screate_simple(rank, dims.data(), maxdims.data()), H5Sclose);
  StepsH5Id props(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Pset_chunk(props.get(), rank, chunk.data());
  if (H5Zfilter_avail(H5Z_FILTER_SHUFFLE) > 0) H5Pset_shuffle(props.get());
  if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) H5Pset_deflate(props.get(), kDeflateLevel);
  StepsH5Id set(H5Dcreate2(file, name, type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), H5Dclose);
  if (set.valid() && columns) set_string_attribute(set.get(), "columns", columns);
  return set;
}

// Appends `rows` rows of `data` (each `row` values) to the extensible array `set`.
bool append_rows(hid_t set, hid_t type, hsize_t written, hsize_t rows, std::span<const hsize_t> inner,
                 const void* data) {
  std::array<hsize_t, 3> dims{}, start{}, count{};
  const int rank = static_cast<int>(inner.size()) + 1;
  dims[0] = written + rows;
  start[0] = written;
  count[0] = rows;
  for (std::size_t i = 0; i < inner.size(); ++i) dims[i + 1] = count[i + 1] = inner[i];
  if (H5Dset_extent(set, dims.data()) < 0) return false;
  StepsH5Id file_space(H5Dget_space(set), H5Sclose);
  if (H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0)
    return false;
  StepsH5Id memory(H5Screate_simple(rank, count.data(), nullptr), H5Sclose);
  return H5Dwrite(set, type, memory.get(), file_space.get(), H5P_DEFAULT, data) >= 0;
}

}  // namespace

kernel::Result<std::unique_ptr<StepsH5>> StepsH5::create(const std::filesystem::path& path, const StepsH5Meta& meta) {
  const std::string where = path.string();
  const auto fail = [&](const std::string& what) { return kernel::Error{"cannot write " + where + ": " + what}; };
  const std::size_t robots = meta.robot_indices.size();
  if (meta.robots.size() != robots) return fail("robot names and indices differ in number");
  auto h = std::make_unique<Handles>();
  h->file = StepsH5Id(H5Fcreate(where.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!h->file.valid()) return fail("HDF5 could not create the file");
  const hid_t f = h->file.get();

  const std::size_t per_step = std::max<std::size_t>(1, robots) * kBytesPerRobotStep;
  std::uint32_t block = kMaxBlock;
  while (block > kMinBlock && block * per_step > kBlockBytes) block /= 2;
  const hsize_t r = robots, rc = std::clamp<hsize_t>(r, 1, kChunkRobots), b = block;

  const hsize_t none[] = {b};
  const hsize_t pose_inner[] = {r, 3}, pose_chunk[] = {b, rc, 3};
  const hsize_t ir_inner[] = {r, sim::kIrCount}, ir_chunk[] = {b, rc, sim::kIrCount};
  const hsize_t wheel_inner[] = {r, 2}, wheel_chunk[] = {b, rc, 2};
  const hsize_t contact_inner[] = {r}, contact_chunk[] = {b, rc};
  h->step = make_array(f, "step", H5T_STD_U64LE, {}, none, nullptr);
  h->time = make_array(f, "time_s", H5T_IEEE_F64LE, {}, none, nullptr);
  h->pose = make_array(f, "pose", H5T_IEEE_F64LE, pose_inner, pose_chunk, "x_cm,y_cm,heading_rad");
  h->ir = make_array(f, "ir", H5T_IEEE_F32LE, ir_inner, ir_chunk, "ir0,ir1,ir2,ir3,ir4,ir5,ir6");
  h->wheels = make_array(f, "wheels", H5T_IEEE_F64LE, wheel_inner, wheel_chunk, "left_cm_s,right_cm_s");
  h->contact = make_array(f, "contact", H5T_STD_U8LE, contact_inner, contact_chunk, nullptr);
  for (const StepsH5Id* set : {&h->step, &h->time, &h->pose, &h->ir, &h->wheels, &h->contact})
    if (!set->valid()) return fail("HDF5 could not create its arrays");

  // The recorded robots: names and world indices, written once (fixed size, contiguous).
  {
    const hsize_t n[] = {r};
    StepsH5Id space(H5Screate_simple(1, n, nullptr), H5Sclose);
    StepsH5Id type = string_type();
    StepsH5Id names(H5Dcreate2(f, "robots", type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose);
    std::vector<const char*> texts;
    for (const std::string& s : meta.robots) texts.push_back(s.c_str());
    StepsH5Id index(H5Dcreate2(f, "robot_index", H5T_STD_U32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                    H5Dclose);
    std::vector<std::uint32_t> indices(meta.robot_indices.begin(), meta.robot_indices.end());
    if (!names.valid() || !index.valid() ||
        (r > 0 && (H5Dwrite(names.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, texts.data()) < 0 ||
                   H5Dwrite(index.get(), H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, indices.data()) < 0)))
      return fail("HDF5 could not write the robots' names");
  }
  bool ok = set_string_attribute(f, "format", "symbricator steps 1") &&
            set_string_attribute(f, "scenario", meta.scenario) &&
            set_string_attribute(f, "scenario_file", meta.scenario_file) &&
            set_number_attribute(f, "seed", H5T_NATIVE_UINT64, static_cast<std::uint64_t>(meta.seed)) &&
            set_number_attribute(f, "control_period_s", H5T_NATIVE_DOUBLE, meta.control_period_s) &&
            set_number_attribute(f, "record_every", H5T_NATIVE_UINT32, meta.record_every) &&
            set_number_attribute(f, "robot_count", H5T_NATIVE_UINT64, static_cast<std::uint64_t>(meta.robot_count)) &&
            set_number_attribute(f, "steps", H5T_NATIVE_UINT64, std::uint64_t{0});
  if (!ok || H5Fflush(f, H5F_SCOPE_LOCAL) < 0) return fail("HDF5 could not write the metadata");
  return std::unique_ptr<StepsH5>(new StepsH5(std::move(h), path, meta.robot_indices, block));
}

StepsH5::StepsH5(std::unique_ptr<Handles> h, std::filesystem::path path, std::vector<std::size_t> robots,
                 std::uint32_t block)
    : h_(std::move(h)), path_(std::move(path)), robots_(std::move(robots)), block_(block) {
  const std::size_t r = robots_.size();
  step_.reserve(block_);
  time_.reserve(block_);
  pose_.reserve(block_ * r * 3);
  ir_.reserve(block_ * r * sim::kIrCount);
  wheels_.reserve(block_ * r * 2);
  contact_.reserve(block_ * r);
}

StepsH5::~StepsH5() = default;

void StepsH5::append(const sim::StepRecord& record, double time_s) {
  if (!h_ || !error_.empty()) return;
  ++steps_;
  step_.push_back(record.step);
  time_.push_back(time_s);
  for (std::size_t i : robots_) {
    const sim::RobotStep& s = record.robots[i];
    pose_.insert(pose_.end(), {s.state.pose.x, s.state.pose.y, s.state.pose.theta});
    for (float v : s.ir)
      ir_.push_back(static_cast<float>(std::nearbyint(static_cast<double>(v) * kIrScale) / kIrScale));
    wheels_.insert(wheels_.end(), {s.state.left_speed, s.state.right_speed});
    contact_.push_back(s.state.in_contact ? 1 : 0);
  }
  if (step_.size() == block_) write_block();
}

void StepsH5::write_block() {
  const hsize_t rows = step_.size();
  if (rows == 0 || !error_.empty()) return;
  const hsize_t r = robots_.size();
  const hsize_t pose_inner[] = {r, 3}, ir_inner[] = {r, sim::kIrCount}, wheel_inner[] = {r, 2}, contact_inner[] = {r};
  const bool ok = append_rows(h_->step.get(), H5T_NATIVE_UINT64, written_, rows, {}, step_.data()) &&
                  append_rows(h_->time.get(), H5T_NATIVE_DOUBLE, written_, rows, {}, time_.data()) &&
                  append_rows(h_->pose.get(), H5T_NATIVE_DOUBLE, written_, rows, pose_inner, pose_.data()) &&
                  append_rows(h_->ir.get(), H5T_NATIVE_FLOAT, written_, rows, ir_inner, ir_.data()) &&
                  append_rows(h_->wheels.get(), H5T_NATIVE_DOUBLE, written_, rows, wheel_inner, wheels_.data()) &&
                  append_rows(h_->contact.get(), H5T_NATIVE_UINT8, written_, rows, contact_inner, contact_.data()) &&
                  set_number_attribute(h_->file.get(), "steps", H5T_NATIVE_UINT64, written_ + rows) &&
                  H5Fflush(h_->file.get(), H5F_SCOPE_LOCAL) >= 0;
  if (!ok) {
    error_ = "cannot write " + path_.string() + ": HDF5 could not append steps (is the disk full?)";
    return;
  }
  written_ += rows;
  step_.clear();
  time_.clear();
  pose_.clear();
  ir_.clear();
  wheels_.clear();
  contact_.clear();
}

kernel::Status StepsH5::close(double simulated_s, bool interrupted) {
  if (!h_) return error_.empty() ? kernel::Status::success() : kernel::Status(kernel::Error{error_});
  write_block();
  if (error_.empty()) {
    const hid_t f = h_->file.get();
    const bool ok =
        set_number_attribute(f, "simulated_s", H5T_NATIVE_DOUBLE, simulated_s) &&
        set_number_attribute(f, "interrupted", H5T_NATIVE_UINT8, static_cast<std::uint8_t>(interrupted ? 1 : 0));
    if (!ok) error_ = "cannot write " + path_.string() + ": HDF5 could not write the closing attributes";
  }
  Handles& h = *h_;
  for (StepsH5Id* set : {&h.step, &h.time, &h.pose, &h.ir, &h.wheels, &h.contact}) set->reset();
  if (h.file.reset() < 0 && error_.empty()) error_ = "cannot write " + path_.string() + ": HDF5 could not close it";
  h_.reset();
  return error_.empty() ? kernel::Status::success() : kernel::Status(kernel::Error{error_});
}

}  // namespace symb::apps::run
