// Module kind files (module_kind_file.hpp): the shipped files give exactly the built-in kinds;
// malformed files are refused with the line and column of the value at fault and a message that
// names the rule; mutants of the shipped files either load as a usable kind or fail at a place
// inside the file; a kind read from a file builds a MuJoCo world that runs.
#include "symb/sim/mujoco/module_kind_file.hpp"

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/source_text.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"

namespace symb::sim::mujoco {
namespace {

const std::string kKindFileDir = std::string(SYMB_SCENARIO_DIR) + "/modules";

std::string kind_file_text(const std::string& name) {
  std::ifstream in(kKindFileDir + "/" + name, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The 1-based line and column of the first `needle` in `text`, as "LINE:COLUMN".
std::string kind_file_place(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  if (at == std::string::npos) return "?";
  const std::size_t line_start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  return std::to_string(line) + ":" + std::to_string(at - line_start + 1);
}

TEST(ModuleKindFile, ShippedFilesAreTheBuiltInKinds) {
  auto cube = load_module_kind(kKindFileDir + "/cube.yaml");
  ASSERT_TRUE(cube.ok()) << cube.error();
  EXPECT_TRUE(*cube == standard_kind());
  auto long_module = load_module_kind(kKindFileDir + "/long.yaml");
  ASSERT_TRUE(long_module.ok()) << long_module.error();
  EXPECT_TRUE(*long_module == long_kind());
  EXPECT_FALSE(*cube == *long_module);
  auto camera = load_module_kind(kKindFileDir + "/camera.yaml");
  ASSERT_TRUE(camera.ok()) << camera.error();
  EXPECT_TRUE(*camera == camera_kind());
  EXPECT_FALSE(*camera == *cube);
  ASSERT_TRUE(camera->camera.has_value());
  ASSERT_TRUE(camera->laser.has_value());
  EXPECT_FALSE(cube->camera.has_value());
  EXPECT_FALSE(cube->laser.has_value());
}

TEST(ModuleKindFile, MissingFileIsNamed) {
  auto k = load_module_kind(kKindFileDir + "/no_such_kind.yaml");
  ASSERT_FALSE(k.ok());
  EXPECT_NE(k.error().find("no_such_kind.yaml: cannot open the module kind file"), std::string::npos) << k.error();
}

// One edit of a shipped file, the text at which the error must point and a fragment of its message.
struct KindFileCase {
  std::string from, to;
  std::string at;  // the first occurrence of this text in the edited file; empty: line 1 column 1
  std::string fragment;
};

// Applies each case's edit to `original` and checks the error's place and message (a case with
// no fragment must load).
void kind_file_expect_errors(const std::string& original, const std::vector<KindFileCase>& cases) {
  for (const KindFileCase& c : cases) {
    std::string text = original;
    const std::size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, c.from.size(), c.to);
    auto k = parse_module_kind(text, "k.yaml");
    if (c.fragment.empty()) {  // only: never crashes, and a failure is located
      EXPECT_TRUE(k.ok()) << k.error();
      continue;
    }
    ASSERT_FALSE(k.ok()) << c.to;
    const std::string where = "k.yaml:" + (c.at.empty() ? std::string("1:1") : kind_file_place(text, c.at)) + ": ";
    EXPECT_EQ(k.error().rfind(where, 0), 0u) << "edit '" << c.to << "': " << k.error() << " (want " << where << ")";
    EXPECT_NE(k.error().find(c.fragment), std::string::npos) << k.error();
  }
}

TEST(ModuleKindFile, MalformedFilesGetLocatedErrors) {
  const std::string cube = kind_file_text("cube.yaml");
  ASSERT_FALSE(cube.empty());
  const std::vector<KindFileCase> cases = {
      {"name: cube", "name: cube\nnmae: x", "nmae", "unknown key 'nmae' in the module kind (did you mean 'name'?)"},
      {"  mass: 0.40", "  mass: -0.4", "-0.4", "body mass (kg) must be in 0.001..100"},
      {"  mass: 0.40", "  mass: .nan", ".nan", "body mass (kg) must be a finite number"},
      {"  mass: 0.40", "  mass: inf", "inf", "must be a finite number"},
      {"  mass: 0.40", "  mass: 1e400", "1e400", "must be a finite number"},
      {"  mass: 0.40", "  mass: [1]", "[1]", "must be a single value, got a sequence"},
      {"[0.10, 0.10, 0.08]", "[0.10, 0, 0.08]", "0, 0.08", "body size (m) y must be in 0.01..2"},
      {"[0.10, 0.10, 0.08]", "[0.10, 0.10]", "[0.10, 0.10]", "body size (m) is [x, y, z]"},
      {"  size: [0.10, 0.10, 0.08]\n", "", "mass: 0.40", "body needs 'size'"},  // at the mapping's first key
      {"  radius: 0.025", "  radius: 0.005", "0.005", "wheel radius must lie between the clearance"},
      {"  width: 0.012", "  width: 0.06", "0.06", "wheel width must be under half the body width"},
      {"  max_speed: 0.15", "  max_speed: 0.0000", "0.0000", "wheel max_speed (m/s) must be in"},
      {"  max_speed: 0.15", "  max_sped: 0.15", "max_sped", "(did you mean 'max_speed'?)"},
      {"wheels:\n  radius: 0.025\n  width: 0.012\n  mass: 0.02\n  max_speed: 0.15\n  gain: 0.05\n", "wheels: nothing\n",
       "nothing", "wheels is a mapping"},
      {"  axis: [0, 1, 0]", "  axis: [0, 0, 0]", "[0, 0, 0]", "hinge axis must not be zero"},
      {"  range: [-1.2, 1.2]", "  range: [1.2, -1.2]", "[1.2, -1.2]", "low < high"},
      {"  range: [-1.2, 1.2]", "  range: [-1.2, 4]", "4]", "hinge range high (rad) must be in"},
      {"  damping: 0.06", "  damping: -0.1", "-0.1", "hinge damping (N*m per rad/s) must be in 0..100"},
      {"{name: back, face: back", "{name: front, face: back", "front, face: back",
       "connector name 'front' is used twice (first at line 22)"},
      {"{name: back, face: back", "{name: 9back, face: back", "9back", "is not a valid name"},
      {"{name: left, face: left", "{name: left, face: lfet", "lfet", "(did you mean 'left'?)"},
      {"position: [0.05, 0, 0]}", "position: [0.06, 0, 0]}", "[0.06, 0, 0]",
       "connector position (m) is not on the front face: its x must be 0.05"},
      {"position: [0.025, 0.05, 0]}", "position: [0.025, 0.05, 0.05]}", "[0.025, 0.05, 0.05]",
       "lies off the left face: its z must be within +-0.04"},
      {"{face: back, position: [-0.05, 0, 0.02]", "{face: front, position: [-0.05, 0, 0.02]",
       "front, position: [-0.05, 0, 0.02]", "two IR sensors on the front face (the first at line 27)"},
      {"range: 0.15}", "range: 0.15, rnage: 1}", "rnage", "unknown key 'rnage' in an IR sensor"},
      {"name: cube", "name: cube\n---\nname: x", "---", "a module kind file holds one YAML document"},
      {"name: cube", "name: [[[[[[[[[[x]]]]]]]]]]", "[[x", "nested more than 8 levels deep"},  // at the 9th
      {"body:\n", "body: &b\n", "", ""},  // an anchor alone changes nothing
      {"  mass: 0.40\n"
       "wheels:\n  radius: 0.025\n  width: 0.012\n  mass: 0.02\n  max_speed: 0.15\n  gain: 0.05\n",
       "  mass: &m 0.40\nwheels: *m\n", "&m",
       "wheels is a mapping"},  // yaml-cpp gives an alias its anchored value's place
  };
  kind_file_expect_errors(cube, cases);
}

// The laser and camera keys, on camera.yaml: each rule's error at its value.
TEST(ModuleKindFile, LaserAndCameraKeysAreChecked) {
  const std::string camera = kind_file_text("camera.yaml");
  ASSERT_FALSE(camera.empty());
  const std::vector<KindFileCase> cases = {
      {"  rays: 15", "  rays: 33", "33", "laser rays must be an integer in 1..32"},
      {"  rays: 15", "  rays: 1.5", "1.5", "laser rays must be an integer"},
      {"  rays: 15", "  rays: 00", "00", "laser rays must be an integer in 1..32"},
      {"  field_of_view: 3.141592653589793", "  field_of_view: 6.5", "6.5", "laser field_of_view (rad) must be in"},
      {"  range: 1.0\n", "  range: 0.0000001\n", "0.0000001", "laser range (m) must be in"},
      {"  position: [0.05, 0, -0.02]", "  position: [0.05, 0, -0.05]", "[0.05, 0, -0.05]",
       "laser position (m) lies off the front face: its z must be within +-0.04"},
      {"  position: [0.05, 0, 0.03]", "  position: [0.04, 0, 0.03]", "[0.04, 0, 0.03]",
       "camera position (m) is not on the front face: its x must be 0.05"},
      {"  width: 32", "  width: 161", "161", "camera width (pixels) must be an integer in 1..160"},
      {"  height: 24", "  height: 121", "121", "camera height (pixels) must be an integer in 1..120"},
      {"  field_of_view: 1.0471975511965976", "  field_of_view: 3.0", "3.0", "camera field_of_view (rad) must be in"},
      {"  range: 2.0", "  rnage: 2.0", "rnage", "unknown key 'rnage' in camera (did you mean 'range'?)"},
      {"  face: front\n  position: [0.05, 0, 0.03]", "  face: top\n  position: [0.05, 0, 0.03]", "top",
       "face must be front, back, left or right"},
      {"camera:\n  face: front\n  position: [0.05, 0, 0.03]\n  width: 32\n  height: 24\n"
       "  field_of_view: 1.0471975511965976\n  range: 2.0\n",
       "camera: [1]\n", "[1]", "camera is a mapping"},
      {"laser:\n  face: front\n  position: [0.05, 0, -0.02]\n  rays: 15\n  field_of_view: 3.141592653589793\n"
       "  range: 1.0\n",
       "laser: nothing\n", "nothing", "laser is a mapping"},
  };
  kind_file_expect_errors(camera, cases);
  // Without the keys the kind is incomplete.
  std::string no_camera = camera.substr(0, camera.find("camera:"));
  auto k = parse_module_kind(no_camera, "k.yaml");
  ASSERT_FALSE(k.ok());
  EXPECT_NE(k.error().find("needs 'camera'"), std::string::npos) << k.error();
}

TEST(ModuleKindFile, BoundsOnSizeAndCounts) {
  const std::string cube = kind_file_text("cube.yaml");
  auto big = parse_module_kind(cube + std::string(kMaxModuleKindBytes, '#'), "k.yaml");
  ASSERT_FALSE(big.ok());
  EXPECT_EQ(big.error().rfind("k.yaml:1:1: ", 0), 0u) << big.error();
  EXPECT_NE(big.error().find("at most 64 KiB"), std::string::npos) << big.error();

  std::string many = cube.substr(0, cube.find("connectors:")) + "connectors:\n";
  for (std::size_t i = 0; i <= kMaxConnectors; ++i)
    many += "  - {name: c" + std::to_string(i) + ", face: front, position: [0.05, 0, 0]}\n";
  many += cube.substr(cube.find("ir:"));
  auto k = parse_module_kind(many, "k.yaml");
  ASSERT_FALSE(k.ok());
  EXPECT_NE(k.error().find("connectors has 17 entries; at most 16"), std::string::npos) << k.error();

  auto empty = parse_module_kind("", "k.yaml");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error(),
            "k.yaml:1:1: the module kind is empty: it needs name, body, wheels, hinge, connectors, ir, laser and "
            "camera");
}

// Mutants of the shipped files: bytes replaced, deleted, duplicated or swapped by a seeded
// stream. Each must load as a kind check() accepts and a world runs, or fail at a line the file
// has.
TEST(ModuleKindFile, MutantsLoadOrFailInsideTheFile) {
  const std::string alphabet = "0123456789-.,:[]{}#&*! \n\tabcefnrx'\"e+";
  std::size_t loaded = 0, refused = 0;
  for (const char* name : {"cube.yaml", "long.yaml", "camera.yaml"}) {
    const std::string original = kind_file_text(name);
    ASSERT_FALSE(original.empty());
    for (std::uint64_t seed = 1; seed <= 400; ++seed) {
      kernel::RandomStream rng(seed);
      std::string text = original;
      const std::uint64_t edits = 1 + rng.below(4);
      for (std::uint64_t e = 0; e < edits && !text.empty(); ++e) {
        const std::size_t pos = rng.below(text.size());
        switch (rng.below(4)) {
          case 0: text[pos] = alphabet[rng.below(alphabet.size())]; break;
          case 1: text.erase(pos, 1 + rng.below(8)); break;
          case 2: text.insert(pos, text.substr(pos, 1 + rng.below(30))); break;
          default: std::swap(text[pos], text[rng.below(text.size())]); break;
        }
      }
      auto k = parse_module_kind(text, "m.yaml");
      if (k.ok()) {
        ++loaded;
        EXPECT_EQ(check(*k), "") << "seed " << seed;
        // What loads, a world takes and runs (0.2 s).
        auto world = MujocoWorld::make({{"a", *k, {0, 0, 0}}});
        ASSERT_TRUE(world.ok()) << "seed " << seed << ": " << world.error() << "\n" << text;
        EXPECT_TRUE(world.value().step(100).ok()) << "seed " << seed << "\n" << text;
        continue;
      }
      ++refused;
      const std::string& e = k.error();
      ASSERT_EQ(e.rfind("m.yaml:", 0), 0u) << e;
      const auto loc = kernel::split_location(std::string_view(e).substr(7));
      ASSERT_TRUE(loc.at.has_value()) << "seed " << seed << ": " << e;
      const auto lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
      EXPECT_GE(loc.at->line, 1u);
      EXPECT_LE(loc.at->line, lines) << "seed " << seed << ": " << e;
      EXPECT_GE(loc.at->column, 1u) << e;
    }
  }
  ::testing::Test::RecordProperty("loaded", static_cast<int>(loaded));
  ::testing::Test::RecordProperty("refused", static_cast<int>(refused));
  // Both outcomes happen: the mutants reach the checks, not only the YAML scanner.
  EXPECT_GT(loaded, 0u);
  EXPECT_GT(refused, 0u);
}

TEST(ModuleKindFile, LoadedKindsRunInAWorld) {
  for (const char* name : {"cube.yaml", "long.yaml", "camera.yaml"}) {
    auto kind = load_module_kind(kKindFileDir + "/" + name);
    ASSERT_TRUE(kind.ok()) << kind.error();
    auto world = MujocoWorld::make({{"a", *kind, {0, 0, 0}}, {"b", *kind, {0.5, 0, 0}}});
    ASSERT_TRUE(world.ok()) << world.error();
    MujocoWorld& w = world.value();
    w.set_hinge_target(0, 0.4);
    auto st = w.step(500);  // 1 s of 2 ms steps
    EXPECT_TRUE(st.ok()) << name << ": " << st.error();
  }
}

// The ends of the ranges the file allows still make a world that runs: a 2 cm module of 10 g on
// the weakest servos, and a 2 m one of 100 kg on the strongest.
TEST(ModuleKindFile, KindsAtTheEndsOfTheRangesRun) {
  const std::vector<std::string> kinds = {
      "name: tiny\nbody: {size: [0.01, 0.01, 0.01], mass: 0.001}\n"
      "wheels: {radius: 0.009, width: 0.001, mass: 0.001, max_speed: 0.001, gain: 0.000001}\n"
      "hinge: {axis: [0, 1, 0], range: [-3.14159, 3.14159], gain: 0.001, damping: 0}\n"
      "connectors: [{name: f, face: front, position: [0.005, 0, 0]}]\nir: []\n"
      "laser: {face: front, position: [0.005, 0, 0], rays: 1, field_of_view: 0.001, range: 0.001}\n"
      "camera: {face: back, position: [-0.005, 0, 0], width: 1, height: 1, field_of_view: 0.001, range: 0.001}\n",
      "name: huge\nbody: {size: [2, 2, 2], mass: 100}\n"
      "wheels: {radius: 1.0, width: 0.9, mass: 100, max_speed: 10, gain: 100}\n"
      "hinge: {axis: [1, 1, 1], range: [-0.1, 0.1], gain: 1000, damping: 100}\n"
      "connectors: [{name: b, face: back, position: [-1, 1, 1]}]\n"
      "ir: [{face: left, position: [1, 1, -1], range: 5}]\n"
      "laser: {face: right, position: [1, -1, 1], rays: 32, field_of_view: 6.283185307179586, range: 10}\n"
      "camera: {face: left, position: [-1, 1, -1], width: 160, height: 120, field_of_view: 2.96705972839036, "
      "range: 10}\n",
  };
  for (const std::string& text : kinds) {
    auto kind = parse_module_kind(text, "k.yaml");
    ASSERT_TRUE(kind.ok()) << kind.error();
    auto world = MujocoWorld::make({{"a", *kind, {0, 0, 0}}, {"b", *kind, {5, 0, 0}}});
    ASSERT_TRUE(world.ok()) << kind->name << ": " << world.error();
    MujocoWorld& w = world.value();
    w.set_hinge_target(0, 0.05);
    auto st = w.step(500);
    EXPECT_TRUE(st.ok()) << kind->name << ": " << st.error();
  }
}

}  // namespace
}  // namespace symb::sim::mujoco
