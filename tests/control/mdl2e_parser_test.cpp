// MDL2e parser and compiler: accepted programs give the expected tree; every error names the line
// and column of the offending token.
#include <gtest/gtest.h>

#include "symb/control/mdl2e/parser.hpp"

#include "mdl2e_test_support.hpp"
#include "support/small_stack.hpp"

namespace symb::control::mdl2e {
namespace {

std::string mdl2e_error(std::string_view source) {
  auto p = compile_source(source);
  return p.ok() ? std::string("<accepted>") : p.error();
}

TEST(Mdl2eParser, ParsesDeclarationsAndNesting) {
  auto a = parse(
      "sensor ir[7]\n"
      "interrupt near = ir[2] >= 1500.5\n"
      "interrupt bump = external\n"
      "behaviour b for 2s loop 3 { atom stop }\n"
      "plan main until near or not bump { behavior inner until (near and bump) { do b } task start logger }\n");
  ASSERT_TRUE(a.ok()) << a.error();
  ASSERT_EQ(a->sensors.size(), 1u);
  EXPECT_EQ(a->sensors[0].size, 7u);
  ASSERT_EQ(a->interrupts.size(), 2u);
  EXPECT_EQ(a->interrupts[0].op, ast::CmpOp::kGe);
  EXPECT_DOUBLE_EQ(a->interrupts[0].threshold, 1500.5);
  EXPECT_TRUE(a->interrupts[1].external);
  ASSERT_EQ(a->behaviours.size(), 1u);
  EXPECT_EQ(a->behaviours[0].mods.duration_ms, 2000u);
  EXPECT_EQ(a->behaviours[0].mods.loop_count, 3u);
  ASSERT_TRUE(a->plan);
  EXPECT_EQ(a->plan->children.size(), 2u);
  EXPECT_EQ(a->plan->children[0].kind, ast::Item::Kind::kBehaviour);
  EXPECT_EQ(a->plan->children[0].children[0].kind, ast::Item::Kind::kCall);
  EXPECT_EQ(a->plan->children[1].kind, ast::Item::Kind::kTask);
  ASSERT_TRUE(a->plan->mods.until);
  EXPECT_EQ(a->plan->mods.until->kind, ast::Expr::Kind::kOr);
}

TEST(Mdl2eParser, DurationsAndUnits) {
  auto a = parse("plan p { atom stop for 1.5s atom stop for 250ms }");
  ASSERT_TRUE(a.ok()) << a.error();
  EXPECT_EQ(a->plan->children[0].mods.duration_ms, 1500u);
  EXPECT_EQ(a->plan->children[1].mods.duration_ms, 250u);
  EXPECT_EQ(mdl2e_error("plan p { atom stop for 10 }"), "1:24: duration '10' needs a unit: ms or s");
  EXPECT_EQ(mdl2e_error("plan p { atom stop for 10h }"), "1:24: unknown duration unit 'h' (use ms or s)");
  EXPECT_EQ(mdl2e_error("plan p { atom stop for 0.5ms }"), "1:24: duration '0.5ms' is not a whole number of ms");
  EXPECT_EQ(mdl2e_error("plan p { atom stop for 0ms }"), "1:24: duration '0ms' must be in 1ms..4000000s");
}

TEST(Mdl2eParser, SyntaxErrorsNameLineAndColumn) {
  EXPECT_EQ(mdl2e_error(""), "1:1: the program has no plan (add 'plan NAME { ... }')");
  EXPECT_EQ(mdl2e_error("plan p {\n  atom forward(100\n}"), "3:1: expected ')' to close the arguments, got '}'");
  EXPECT_EQ(mdl2e_error("plan p {\n  atom forward(100)\n"),
            "3:1: expected '}' to close the body, got the end of the program");
  EXPECT_EQ(mdl2e_error("plan p { }"), "1:10: a body needs at least one atom, behaviour, 'do', 'task' or 'device'");
  EXPECT_EQ(mdl2e_error("plan p { atom stop }\n@"), "2:1: unexpected character '@'");
  EXPECT_EQ(mdl2e_error("plan p { atom stop }\x01"), "1:21: unexpected byte 0x01");
  EXPECT_EQ(mdl2e_error("plan p { atom stop until }"),
            "1:26: expected an interrupt name, 'not', 'true', 'false' or '(', got '}'");
  EXPECT_EQ(mdl2e_error("plan p { atom stop } plan q { atom stop }"),
            "1:22: a program has exactly one plan; another was defined at line 1");
  EXPECT_EQ(mdl2e_error("plan p { atom stop for 1s for 2s }"), "1:27: 'for' given twice");
  EXPECT_EQ(mdl2e_error("plan loop { atom stop }"), "1:6: expected a plan name, got the keyword 'loop'");
  EXPECT_EQ(mdl2e_error("sensor ir[0]\nplan p { atom stop }"), "1:11: channel size must be in 1..256, got '0'");
  EXPECT_EQ(mdl2e_error("plan p { task stop x }"),
            "1:15: expected start, suspend, resume or delete after 'task', got 'stop'");
  EXPECT_EQ(mdl2e_error("plan p { device }"), "1:17: expected a device name, got '}'");
  EXPECT_EQ(mdl2e_error("plan p { device connector_front }"),
            "1:33: expected a command of device 'connector_front', got '}'");
  EXPECT_EQ(mdl2e_error("plan p { device hinge set 2 3 }"),
            "1:29: expected 'atom', 'behaviour', 'do', 'task', 'device' or '}', got '3'");
  EXPECT_EQ(mdl2e_error("plan p { device hinge set 2e9 }"), "1:27: argument takes no unit, got '2e9'");
  EXPECT_EQ(mdl2e_error("plan p { device hinge set 2000000 }"), "1:27: argument must be within +-1000000");
  EXPECT_EQ(mdl2e_error("plan p { atom stop } 12"),
            "1:22: expected 'sensor', 'interrupt', 'behaviour' or 'plan', got '12'");
  EXPECT_EQ(mdl2e_error("plan p { atom wheels(1.) }"), "1:24: expected a digit after the decimal point");
}

TEST(Mdl2eParser, NameErrorsNameLineColumnAndSuggest) {
  EXPECT_EQ(mdl2e_error("plan p {\n  atom forwrd(1)\n}"),
            "2:8: unknown primitive behaviour 'forwrd' (did you mean 'forward'?)");
  EXPECT_EQ(mdl2e_error("plan p { atom forward }"),
            "1:15: 'forward' takes 1 argument, got 0 (forward(speed): both wheels at speed)");
  EXPECT_EQ(mdl2e_error("sensor ir[3]\ninterrupt near = ir[1] > 5\nplan p { atom stop until naer }"),
            "3:26: unknown interrupt 'naer' (did you mean 'near'?)");
  EXPECT_EQ(mdl2e_error("sensor ir[3]\ninterrupt near = ir[3] > 5\nplan p { atom stop }"),
            "2:21: index 3 is out of range for ir[3]");
  EXPECT_EQ(mdl2e_error("sensor ir[3]\ninterrupt near = it[1] > 5\nplan p { atom stop }"),
            "2:18: unknown sensor channel 'it' (did you mean 'ir'?)");
  EXPECT_EQ(mdl2e_error("behaviour avoid { atom stop }\nplan p { do aviod }"),
            "2:13: unknown behaviour 'aviod' (did you mean 'avoid'?)");
  EXPECT_EQ(mdl2e_error("behaviour a { do b }\nbehaviour b { do a }\nplan p { do a }"),
            "2:18: behaviour 'a' calls itself (recursion is not allowed)");
  EXPECT_EQ(mdl2e_error("plan p loop { task start x }"),
            "1:8: 'p' loops forever but contains no atom, so it would never wait");
  EXPECT_EQ(mdl2e_error("plan p { atom stop loop }"), "1:20: an atom cannot loop (put it in a behaviour)");
  EXPECT_EQ(mdl2e_error("sensor ir[1]\nsensor ir[2]\nplan p { atom stop }"), "2:1: sensor 'ir' is declared twice");
}

TEST(Mdl2eParser, DeepNestingIsBoundedNotACrash) {
  std::string deep = "plan p ";
  for (int i = 0; i < 20; ++i) deep += "{ behaviour ";
  deep += "{ atom stop }";
  for (int i = 0; i < 20; ++i) deep += " }";
  const std::string e = mdl2e_error(deep);
  EXPECT_NE(e.find("nested deeper than 16 levels"), std::string::npos) << e;

  std::string huge = "plan p ";
  for (int i = 0; i < 10000; ++i) huge += "{ behaviour ";
  EXPECT_NE(mdl2e_error(huge).find("behaviours nested too deeply"), std::string::npos);

  std::string expr = "interrupt a = external\nplan p { atom stop until ";
  for (int i = 0; i < 10000; ++i) expr += "not (";
  EXPECT_NE(mdl2e_error(expr).find("interrupt expression nested too deeply"), std::string::npos);

  std::string wide = "interrupt a = external\nplan p { atom stop until a";
  for (int i = 0; i < 20; ++i) wide += " or (a";
  for (int i = 0; i < 20; ++i) wide += ")";
  wide += " }";
  EXPECT_NE(mdl2e_error(wide).find("stack slots"), std::string::npos) << mdl2e_error(wide);
}

// A chain of and/or is long, not deep: the parser keeps it flat and the compiler walks it with an
// explicit stack, so a chain as long as the byte code holds compiles and runs, and a longer one is
// a located error, never a stack overflow.
TEST(Mdl2eParser, LongAndOrChainCompilesWithoutRecursion) {
  constexpr int kTerms = 19000;  // 3 bytes each: just under the 60,000 bytes of expression code
  std::string chain = "sensor ir[2]\ninterrupt a = ir[0] > 1\ninterrupt b = ir[1] > 1\nplan p { atom stop until a";
  for (int i = 1; i < kTerms; ++i) chain += i % 2 ? " or b" : " and a";
  chain += " }\n";
  auto program = compile_source(chain);
  ASSERT_TRUE(program.ok()) << program.error();
  using testing::events;
  using testing::ms;
  Interpreter in(*program);
  std::vector<double> sensors{0, 0};
  (void)in.step(ms(0), {.sensors = sensors});
  sensors[1] = 5;  // the last term is 'or b': the chain turns true
  const Output out = in.step(ms(1), {.sensors = sensors});
  EXPECT_EQ(events(out), "interrupted:stop completed:p plan_ended:p");

  std::string longer = "interrupt a = external\nplan p { atom stop until a";
  for (int i = 1; i < 150000; ++i) longer += " or a";
  longer += " }\n";
  EXPECT_NE(mdl2e_error(longer).find("interrupt expressions are too large in all"), std::string::npos)
      << mdl2e_error(longer);
  EXPECT_EQ(mdl2e_error(longer).rfind("2:", 0), 0u) << mdl2e_error(longer);
}

// The deepest programs each bound lets through, and the longest chain, compile on a thread with
// 1/32 of the executors' default stack: the bounds leave ample headroom, with ASan's frames too.
TEST(Mdl2eParser, TheDeepestAcceptedProgramsFitASmallStack) {
  std::string bodies = "plan p ";
  for (int i = 0; i < kMaxDepth - 2; ++i) bodies += "{ behaviour ";
  bodies += "{ atom stop }";
  for (int i = 0; i < kMaxDepth - 2; ++i) bodies += " }";
  std::string parens = "interrupt a = external\nplan p { atom stop until ";
  for (int i = 0; i < kMaxExprNesting; ++i) parens += i % 2 ? "not " : "(";
  parens += "a";
  for (int i = 0; i < kMaxExprNesting; i += 2) parens += ")";
  parens += " }";
  std::string deep_parse = "plan p ";  // rejected by the compiler's depth, after the parser's deepest
  for (int i = 0; i < kMaxParseNesting - 1; ++i) deep_parse += "{ behaviour ";
  deep_parse += "{ atom stop }";
  for (int i = 0; i < kMaxParseNesting - 1; ++i) deep_parse += " }";
  std::string chain = "interrupt a = external\nplan p { atom stop until a";
  for (int i = 1; i < 19000; ++i) chain += " or not a";
  chain += " }";
  std::string results[4];
  ASSERT_TRUE(test_support::run_on_small_stack([&] {
    results[0] = mdl2e_error(bodies);
    results[1] = mdl2e_error(parens);
    results[2] = mdl2e_error(deep_parse);
    results[3] = mdl2e_error(chain);
  }));
  EXPECT_EQ(results[0], "<accepted>");
  EXPECT_EQ(results[1], "<accepted>");
  EXPECT_NE(results[2].find("nested deeper than 16 levels"), std::string::npos) << results[2];
  EXPECT_NE(results[3].find("interrupt expressions are too large in all"), std::string::npos) << results[3];
}

}  // namespace
}  // namespace symb::control::mdl2e
