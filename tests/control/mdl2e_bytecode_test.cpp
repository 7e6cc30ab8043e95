// MDL2e byte code: compile -> encode -> decode gives the same program and listing; corrupted or
// truncated byte code is rejected by decode()/verify(), never crashes.
#include <random>

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
  EXPECT_NE(listing.find("ATOM wheels(-1.5, 2.25)"), std::string::npos) << listing;
  EXPECT_NE(listing.find("INTERRUPT 0 near = sensor[2] > 2000"), std::string::npos) << listing;
  EXPECT_LT(bytes.size(), 400u);  // compact
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

}  // namespace
}  // namespace symb::control::mdl2e
