// MDL2e byte code: compile -> encode -> decode gives the same program and listing; corrupted or
// truncated byte code is rejected by decode()/verify(), never crashes.
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "mdl2e_test_support.hpp"

namespace symb::control::mdl2e {
namespace {

const char* kProgram = R"(
sensor ir[7]
interrupt near = ir[2] > 2000
interrupt bump = external
behaviour avoid for 800ms { atom backward(80) for 300ms atom turn(60) for 500ms }
plan main loop until bump {
  atom forward(100) until near or not (bump and near)
  do avoid
  task start logger
  device connector_front latch
  device hinge set -0.25
  atom wheels(-1.5, 2.25)
})";

TEST(Mdl2eBytecode, RoundTripAndDisassembly) {
  const Program p = testing::must_compile(kProgram);
  ASSERT_TRUE(verify(p).ok()) << verify(p).error();
  const auto bytes = encode(p);
  auto back = decode(bytes);
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_TRUE(*back == p);
  EXPECT_EQ(encode(*back), bytes);
  const std::string listing = disassemble(*back);
  EXPECT_EQ(listing, disassemble(p));
  EXPECT_NE(listing.find("PLAN main interrupt=[bump]@0 loop"), std::string::npos) << listing;
  EXPECT_NE(listing.find("ATOM forward(100) interrupt=[near bump near AND NOT OR]"), std::string::npos) << listing;
  EXPECT_NE(listing.find("BEHAVIOUR avoid duration=800ms"), std::string::npos) << listing;
  EXPECT_NE(listing.find("TASK start logger"), std::string::npos) << listing;
  EXPECT_NE(listing.find("DEVICE connector_front latch\n"), std::string::npos) << listing;
  EXPECT_NE(listing.find("DEVICE hinge set -0.25\n"), std::string::npos) << listing;
  EXPECT_NE(listing.find("ATOM wheels(-1.5, 2.25)"), std::string::npos) << listing;
  EXPECT_NE(listing.find("INTERRUPT 0 near = sensor[2] > 2000"), std::string::npos) << listing;
  EXPECT_LT(bytes.size(), 480u);  // compact
}

TEST(Mdl2eBytecode, DecodedProgramRunsLikeTheOriginal) {
  const Program p = testing::must_compile(kProgram);
  auto back = decode(encode(p));
  ASSERT_TRUE(back.ok());
  Interpreter a(p), b(*back);
  std::array<double, 7> ir{};
  for (int k = 0; k < 500; ++k) {
    ir[2] = (k / 37) % 2 ? 2500 : 0;
    const InterruptInputs in{ir, k > 450 ? 1u : 0u};
    auto oa = a.step(testing::ms(k * 10), in);
    auto ob = b.step(testing::ms(k * 10), in);
    ASSERT_EQ(testing::atom(oa), testing::atom(ob));
    ASSERT_EQ(testing::events(oa), testing::events(ob));
  }
}

TEST(Mdl2eBytecode, CorruptBytesAreRejectedNotCrashed) {
  const auto bytes = encode(testing::must_compile(kProgram));
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    auto r = decode(std::span(bytes.data(), n));
    EXPECT_FALSE(r.ok()) << n;
  }
  std::mt19937 rng(7);
  int accepted = 0;
  for (int k = 0; k < 5000; ++k) {
    auto b = bytes;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) b[rng() % b.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
    auto r = decode(b);
    if (!r.ok()) {
      EXPECT_EQ(r.error().rfind("bytecode: ", 0), 0u) << r.error();
      continue;
    }
    ++accepted;  // a flip that still verifies (a changed speed, say) must still run safely
    Interpreter in(*r);
    for (int t = 0; t < 50; ++t) (void)in.step(testing::ms(t * 7), InterruptInputs{{}, static_cast<std::uint64_t>(t)});
  }
  EXPECT_LT(accepted, 5000);
}

TEST(Mdl2eBytecode, VerifyCatchesBadTrees) {
  Program p = testing::must_compile("plan p { atom stop atom stop }");
  Program cyc = p;
  cyc.nodes[2].next_sibling = 1;
  EXPECT_FALSE(verify(cyc).ok());
  Program bad_expr = p;
  bad_expr.code = {static_cast<std::uint8_t>(ExprOp::kAnd), 0};
  bad_expr.nodes[1].expr = 0;
  EXPECT_FALSE(verify(bad_expr).ok());
  Program bad_arity = p;
  bad_arity.nodes[1].arg = static_cast<std::uint16_t>(Primitive::kWheels);
  EXPECT_FALSE(verify(bad_arity).ok());
}

TEST(Mdl2eBytecode, VerifyCatchesBadDeviceActions) {
  const Program p = testing::must_compile("plan p { device hinge set 0.5 atom stop }");
  ASSERT_EQ(p.nodes[1].op, Op::kDevice);
  ASSERT_TRUE(verify(p).ok());
  Program bad_command = p;
  bad_command.nodes[1].arg = static_cast<std::uint16_t>(p.strings.size());
  EXPECT_FALSE(verify(bad_command).ok());
  Program two_arguments = p;
  two_arguments.params.push_back(1);
  two_arguments.nodes[1].param_count = 2;
  EXPECT_FALSE(verify(two_arguments).ok());
  Program nan_argument = p;
  nan_argument.params[nan_argument.nodes[1].param_offset] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(verify(nan_argument).ok());
  Program timed = p;
  timed.nodes[1].duration_ms = 5;
  EXPECT_FALSE(verify(timed).ok());
}

TEST(Mdl2eBytecode, ADeviceActionIsAnInstantEventWithItsCommandAndArgument) {
  const Program p = testing::must_compile("plan p { device connector_front latch device hinge set 0.5 atom stop }");
  Interpreter in(p);
  const Output out = in.step(testing::ms(0), {});
  std::vector<const Event*> actions;
  for (const Event& e : out.event_list())
    if (e.kind == EventKind::kDeviceAction) actions.push_back(&e);
  ASSERT_EQ(actions.size(), 2u);
  EXPECT_EQ(actions[0]->name, "connector_front");
  EXPECT_EQ(actions[0]->command, "latch");
  EXPECT_FALSE(actions[0]->has_argument);
  EXPECT_EQ(actions[1]->name, "hinge");
  EXPECT_EQ(actions[1]->command, "set");
  EXPECT_TRUE(actions[1]->has_argument);
  EXPECT_EQ(actions[1]->argument, 0.5f);
  EXPECT_EQ(testing::atom(out), "stop");
}

}  // namespace
}  // namespace symb::control::mdl2e
