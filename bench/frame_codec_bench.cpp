// frame_codec_bench: throughput of the frame codec (COBS + CRC-16 + version byte, io/frame_codec),
// encode and decode, for payloads of 8, 64 and 1024 bytes, against plain memcpy of the same
// payload bytes in the same pieces, measured in the same run. Every figure is payload MB/s
// (10^6 bytes of payload per CPU second). Decoding is checked: every frame must come out, none
// may be dropped, or the run fails. Target: encode and decode each >= 25 % of memcpy at 1024
// bytes (the bulk case; a serial link at 4 Mbit/s needs 0.5 MB/s, so this is about headroom for
// a board that routes many links and for TCP).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/io/frame_codec.hpp"
#include "symb/kernel/random_stream.hpp"

#include "bench_report.hpp"

namespace {

using namespace symb;

constexpr std::int64_t kHeadline = 1024;
constexpr double kTargetRatio = 0.25;
// Each iteration handles about this many payload bytes, so that the
// per-iteration overhead of the benchmark loop is the same small share at every size.
constexpr std::size_t kBatchBytes = std::size_t{64} * 1024;

std::vector<std::byte> random_bytes(std::size_t n, std::uint64_t seed) {
  kernel::RandomStream rnd(seed, n);
  std::vector<std::byte> v(n);
  // Uniform over all 256 values: a zero about once in 256 bytes, so most COBS blocks are full.
  for (auto& b : v) b = static_cast<std::byte>(rnd.below(256));
  return v;
}

std::size_t frames_per_batch(std::size_t n) { return std::max<std::size_t>(1, kBatchBytes / n); }

void BM_Encode(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::size_t k = frames_per_batch(n);
  const std::vector<std::byte> payloads = random_bytes(n * k, 1);
  // One reusable buffer, as a sender keeps: the span form allocates and zero-fills nothing.
  std::vector<std::byte> out(io::max_encoded_size(n) * k);
  for (auto _ : state) {
    std::size_t at = 0;
    for (std::size_t i = 0; i < k; ++i)
      at += io::encode_frame({payloads.data() + i * n, n}, std::span<std::byte>(out.data() + at, out.size() - at));
    benchmark::DoNotOptimize(out.data());
    benchmark::DoNotOptimize(at);
    benchmark::ClobberMemory();
  }
  state.counters["MBps"] = benchmark::Counter(
      static_cast<double>(n * k) * static_cast<double>(state.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

void BM_Decode(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::size_t k = frames_per_batch(n);
  const std::vector<std::byte> payloads = random_bytes(n * k, 1);
  std::vector<std::byte> stream;
  for (std::size_t i = 0; i < k; ++i) io::encode_frame({payloads.data() + i * n, n}, stream);
  io::FrameDecoder decoder(n);
  std::size_t frames = 0;
  std::size_t sum = 0;
  for (auto _ : state) {
    decoder.feed(stream, [&](std::span<const std::byte> f) {
      ++frames;
      sum += f.size();
    });
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(sum);
  const auto expected = static_cast<std::size_t>(state.iterations()) * k;
  if (frames != expected || decoder.stats().dropped() != 0 || sum != expected * n) {
    std::string error = "decoded " + std::to_string(frames) + " of " + std::to_string(expected) + " frames, dropped ";
    error += std::to_string(decoder.stats().dropped());
    state.SkipWithError(error.c_str());
    return;
  }
  state.counters["MBps"] = benchmark::Counter(
      static_cast<double>(n * k) * static_cast<double>(state.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

// The baseline: the same payload bytes copied in the same pieces, each with a memcpy call the
// compiler cannot merge with the next (the destination is clobbered after each).
void BM_Memcpy(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const std::size_t k = frames_per_batch(n);
  const std::vector<std::byte> payloads = random_bytes(n * k, 1);
  std::vector<std::byte> out(n * k);
  for (auto _ : state) {
    for (std::size_t i = 0; i < k; ++i) {
      std::memcpy(out.data() + i * n, payloads.data() + i * n, n);
      benchmark::ClobberMemory();
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["MBps"] = benchmark::Counter(
      static_cast<double>(n * k) * static_cast<double>(state.iterations()) / 1e6, benchmark::Counter::kIsRate);
}

constexpr int kRepetitions = 5;

BENCHMARK(BM_Encode)->Arg(8)->Arg(64)->Arg(kHeadline)->Repetitions(kRepetitions)->MinTime(0.2);
BENCHMARK(BM_Decode)->Arg(8)->Arg(64)->Arg(kHeadline)->Repetitions(kRepetitions)->MinTime(0.2);
BENCHMARK(BM_Memcpy)->Arg(8)->Arg(64)->Arg(kHeadline)->Repetitions(kRepetitions)->MinTime(0.2);

}  // namespace

int main(int argc, char** argv) {
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;

  std::printf("\nframe codec, payload MB/s (CPU time), median of repetitions\n");
  std::printf("%8s %12s %12s %12s %10s %10s\n", "payload", "encode", "decode", "memcpy", "enc/cpy", "dec/cpy");
  for (std::int64_t size : {std::int64_t{8}, std::int64_t{64}, kHeadline}) {
    const std::string a = "/" + std::to_string(size);
    const double enc = reporter.median("BM_Encode" + a, "MBps");
    const double dec = reporter.median("BM_Decode" + a, "MBps");
    const double cpy = reporter.median("BM_Memcpy" + a, "MBps");
    std::printf("%8lld %12.1f %12.1f %12.1f %9.1f%% %9.1f%%\n", static_cast<long long>(size), enc, dec, cpy,
                cpy > 0 ? 100 * enc / cpy : 0.0, cpy > 0 ? 100 * dec / cpy : 0.0);
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());

  const std::string h = "/" + std::to_string(kHeadline);
  const double enc = reporter.median("BM_Encode" + h, "MBps");
  const double dec = reporter.median("BM_Decode" + h, "MBps");
  const double cpy = reporter.median("BM_Memcpy" + h, "MBps");
  const double enc_ratio = cpy > 0 ? enc / cpy : 0.0;
  const double dec_ratio = cpy > 0 ? dec / cpy : 0.0;
  const bool met = enc_ratio >= kTargetRatio && dec_ratio >= kTargetRatio && reporter.errors().empty();
  std::printf(
      "frame codec (%lld-byte payloads): encode %.0f MB/s, decode %.0f MB/s, memcpy %.0f MB/s, ratio encode %.1f%%, "
      "decode %.1f%%, target >= %.0f%%: %s\n",
      static_cast<long long>(kHeadline), enc, dec, cpy, 100 * enc_ratio, 100 * dec_ratio, 100 * kTargetRatio,
      met ? "MET" : "NOT MET");
  return 0;
}
