#include "symb/io/device.hpp"

#include <gtest/gtest.h>

namespace symb::io {
namespace {

// A device with one command of each shape, recording what it was asked.
class Lamp final : public Device {
 public:
  Lamp() : Device("lamp") {
    add_ioctl(
        {"brightness", os::ParamSpec{"level", os::ParamType::kInt, std::int64_t{0}, 0.0, 255.0, ""}, "sets the level"},
        [this](const os::ParamValue* v) -> kernel::Result<std::string> {
          level = std::get<std::int64_t>(*v);
          return std::to_string(level);
        });
    add_ioctl(
        {"status", std::nullopt, "reports the level"},
        [this](const os::ParamValue*) -> kernel::Result<std::string> { return "level " + std::to_string(level); });
  }
  kernel::Status open() override {
    open_ = true;
    return {};
  }
  void close() override { open_ = false; }
  bool is_open() const override { return open_; }
  std::int64_t level = 0;

 private:
  bool open_ = false;
};

TEST(Device, TypedIoctlsByName) {
  Lamp lamp;
  auto r = lamp.ioctl("brightness", "200");
  ASSERT_TRUE(r) << r.error();
  EXPECT_EQ(*r, "200");
  EXPECT_EQ(lamp.level, 200);
  EXPECT_EQ(*lamp.ioctl("status"), "level 200");
  EXPECT_TRUE(lamp.ioctl_value("brightness", os::ParamValue{std::int64_t{7}}));
  EXPECT_EQ(lamp.level, 7);
  ASSERT_EQ(lamp.ioctls().size(), 2u);
  EXPECT_EQ(lamp.ioctls()[0].name, "brightness");
}

TEST(Device, BadIoctlsAreErrorsNamingDeviceAndCommand) {
  Lamp lamp;
  auto unknown = lamp.ioctl("brightnes", "1");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().find("device 'lamp' has no ioctl 'brightnes' (did you mean 'brightness'?)"),
            std::string::npos)
      << unknown.error();
  EXPECT_FALSE(lamp.ioctl("brightness", "300"));                      // out of range
  EXPECT_FALSE(lamp.ioctl("brightness", "bright"));                   // wrong type
  EXPECT_FALSE(lamp.ioctl("brightness"));                             // missing argument
  EXPECT_FALSE(lamp.ioctl("status", "1"));                            // argument not taken
  EXPECT_FALSE(lamp.ioctl_value("brightness", os::ParamValue{2.5}));  // wrong C++ type
  EXPECT_EQ(lamp.level, 0);
}

}  // namespace
}  // namespace symb::io
