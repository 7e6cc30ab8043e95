// DepthImage: a small camera frame as a message blob: per pixel the distance to what the pixel
// sees (m) and that thing's object id (a simulator's labels: in the 3D world a module's index + 1,
// a static obstacle's negative id, 0 for the floor or nothing). It is made once per frame and
// shared, immutable, by every task hooked to the camera's sensor task: a 32 x 24 frame is 6 KB,
// too much for a message's inline numbers and too much to copy per receiver.
//
// A camera sensor publishes its few summary numbers with the frame attached (Sensor::publish
// with a blob); its SensorTask sends both in one message, and a receiver reads the frame with
// depth_image_of(message).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "symb/os/message.hpp"

namespace symb::robot {

class DepthImage final : public os::Blob {
 public:
  static constexpr std::uint32_t kKind = 0x44455054;  // "DEPT"
  std::uint32_t kind() const override { return kKind; }

  DepthImage(std::size_t w, std::size_t h) : width(w), height(h), depth(w * h), ids(w * h) {}

  // Row v from the top, column u from the left.
  float depth_at(std::size_t u, std::size_t v) const { return depth[v * width + u]; }
  std::int32_t id_at(std::size_t u, std::size_t v) const { return ids[v * width + u]; }

  std::size_t width;
  std::size_t height;
  std::vector<float> depth;       // m, width x height, row by row from the top
  std::vector<std::int32_t> ids;  // object ids, the same layout
};

// The frame a message carries, or nullptr when it carries none.
inline const DepthImage* depth_image_of(const os::Message& m) { return os::blob_as<DepthImage>(m.payload.blob.get()); }

}  // namespace symb::robot
