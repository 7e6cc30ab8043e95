// WorldSpec: a 2D world as plain data (the MuJoCo mjModel idea): a rectangular arena with walls
// around it, straight inner wall segments (a maze), and where robots start. Backends (Enki today)
// build their own running state from it; scenario files describe it; nothing here runs.
//
// Units are Enki's: centimetres and radians. The arena spans [0, width] x [0, height]; x grows to
// the right, y upwards; an angle of 0 faces +x and grows counter-clockwise.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace symb::sim {

// A point in a text file: where a value came from, for error messages ("file:line:column").
struct SourceLocation {
  std::string file;
  int line = 0;             // 1-based; 0 when unknown
  int column = 0;           // 1-based; 0 when unknown
  std::string str() const;  // "file:line:column", or as much of it as is known
};

struct Pose {
  double x = 0;
  double y = 0;
  double theta = 0;
};

// A straight wall from (x1, y1) to (x2, y2), `thickness` wide, centred on that segment.
struct WallSpec {
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;
  double thickness = 2.0;
  SourceLocation where;
};

// A marked floor area (tape, paint, a printed target) that the robots' ground sensors see: a
// rectangle [x1, x2] x [y1, y2] or a disc. The plain floor reflects 1; a zone reflects `ground`
// (0 black .. 1 white). Where zones overlap, the one listed last is on top.
struct ZoneSpec {
  enum class Shape : std::uint8_t { kRect, kCircle };
  Shape shape = Shape::kRect;
  double x1 = 0, y1 = 0, x2 = 0, y2 = 0;  // kRect, x1 <= x2 and y1 <= y2
  double cx = 0, cy = 0, radius = 0;      // kCircle
  double ground = 0.1;
  std::string name;  // for pictures and messages; may be empty
  SourceLocation where;

  bool contains(double x, double y) const {
    if (shape == Shape::kRect) return x >= x1 && x <= x2 && y >= y1 && y <= y2;
    return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= radius * radius;
  }
};

// A short-range radio shared by the world's robots (sim::LocalRadio): every robot gets a device
// task `radio` on it. Range centre to centre; walls do not block it.
struct RadioSpec {
  double range = 50;                          // cm
  std::size_t max_message_bytes = 64 * 1024;  // longer messages are refused
};

// The physics behind a 2D world (see sim/world_factory.hpp). Enki is the reference; Box2D is for
// swarms of thousands (its step costs about the same per robot at any size).
enum class Engine2d : std::uint8_t { kEnki, kBox2d };

struct WorldSpec {
  Engine2d engine = Engine2d::kEnki;
  double width = 0;                // cm
  double height = 0;               // cm
  double wall_height = 10.0;       // cm; Thymio2's IR sensors see objects at least as high as they are
  std::vector<WallSpec> walls;     // inner walls; the arena's four sides are always walled
  std::vector<ZoneSpec> zones;     // marked floor areas
  std::optional<RadioSpec> radio;  // none: the robots have no radio
};

// The robot models a world can hold.
enum class RobotKind : std::uint8_t { kThymio2 };

}  // namespace symb::sim
