#include "symb/io/frame_codec.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace symb::io {

namespace {

// CRC-16/CCITT-FALSE: polynomial G(x) = x^16 + x^12 + x^5 + 1, not reflected, no final xor.
constexpr std::uint32_t kPoly = 0x11021;

// Slicing-by-8: eight bytes per step through eight tables (4 KiB), whose lookups are
// independent, instead of a chain of eight dependent lookups. kCrcTables[k][v] is the CRC register
// after byte v followed by k zero bytes, starting from 0; the CRC is linear, so a step is the xor
// of one lookup per byte, with the register folded into the first two bytes. (A microcontroller
// short of flash can keep only the first table and the byte loop below: 512 bytes.)
constexpr std::array<std::array<std::uint16_t, 256>, 8> kCrcTables = [] {
  std::array<std::array<std::uint16_t, 256>, 8> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i << 8;
    for (int k = 0; k < 8; ++k) c = (c & 0x8000) != 0 ? (c << 1) ^ kPoly : c << 1;
    t[0][i] = static_cast<std::uint16_t>(c);
  }
  for (std::size_t k = 1; k < 8; ++k)
    for (std::size_t i = 0; i < 256; ++i) {
      const std::uint16_t r = t[k - 1][i];
      t[k][i] = static_cast<std::uint16_t>((r << 8) ^ t[0][r >> 8]);
    }
  return t;
}();

std::uint16_t crc_bytewise(const std::byte* p, std::size_t n, std::uint16_t crc) {
  const auto& t = kCrcTables;
  auto at = [p](std::size_t i) { return static_cast<unsigned>(p[i]); };
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8)
    crc = static_cast<std::uint16_t>(t[7][at(i) ^ (crc >> 8)] ^ t[6][at(i + 1) ^ (crc & 0xff)] ^ t[5][at(i + 2)] ^
                                     t[4][at(i + 3)] ^ t[3][at(i + 4)] ^ t[2][at(i + 5)] ^ t[1][at(i + 6)] ^
                                     t[0][at(i + 7)]);
  for (; i < n; ++i) crc = static_cast<std::uint16_t>((crc << 8) ^ t[0][((crc >> 8) ^ at(i)) & 0xff]);
  return crc;
}

#if defined(__x86_64__)
// x^n mod G(x), for the folding constants below.
constexpr std::uint64_t xpow_mod(unsigned n) {
  std::uint32_t r = 1;
  for (unsigned i = 0; i < n; ++i) {
    r <<= 1;
    if ((r & 0x10000) != 0) r ^= kPoly;
  }
  return r;
}

#define SYMB_CLMUL __attribute__((target("pclmul,ssse3")))

// The first byte becomes the top of the polynomial, as a non-reflected CRC reads it.
SYMB_CLMUL inline __m128i load_reversed(const std::byte* p) {
  const __m128i reverse = _mm_set_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  return _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)), reverse);
}

SYMB_CLMUL inline __m128i fold(__m128i a, __m128i k) {
  return _mm_xor_si128(_mm_clmulepi64_si128(a, k, 0x11), _mm_clmulepi64_si128(a, k, 0x00));
}

// floor(x^64 / G(x)), for Barrett reduction of a 64-bit polynomial modulo G.
constexpr std::uint64_t barrett_mu() {
  unsigned __int128 r = static_cast<unsigned __int128>(1) << 64;
  std::uint64_t q = 0;
  for (int bit = 64; bit >= 16; --bit)
    if (((r >> bit) & 1) != 0) {
      q |= std::uint64_t{1} << (bit - 16);
      r ^= static_cast<unsigned __int128>(kPoly) << (bit - 16);
    }
  return q;
}

// A * x^16 mod G for a 128-bit A: the CRC register after the data A stands for. Three folds
// bring A down to 64 bits, then Barrett's method divides without a loop: q = floor(U / G) is
// floor(floor(U / x^16) * mu / x^48), exactly, as polynomials have no carries.
SYMB_CLMUL inline std::uint16_t reduce(__m128i a) {
  constexpr std::uint64_t kX80 = xpow_mod(80), kX64 = xpow_mod(64), kMu = barrett_mu();
  const __m128i k = _mm_set_epi64x(static_cast<long long>(kX64), static_cast<long long>(kX80));
  // A_hi * (x^80 mod G) + A_lo * x^16: at most 80 bits.
  __m128i t = _mm_xor_si128(_mm_clmulepi64_si128(a, k, 0x01), _mm_slli_si128(_mm_move_epi64(a), 2));
  // Bits 64..79 times (x^64 mod G), plus bits 0..63: 64 bits.
  const __m128i u = _mm_xor_si128(_mm_clmulepi64_si128(t, k, 0x11), _mm_move_epi64(t));
  const __m128i m = _mm_set_epi64x(static_cast<long long>(kPoly), static_cast<long long>(kMu));
  const __m128i q = _mm_srli_si128(_mm_clmulepi64_si128(_mm_srli_epi64(u, 16), m, 0x00), 6);
  const __m128i r = _mm_xor_si128(u, _mm_clmulepi64_si128(q, m, 0x10));
  return static_cast<std::uint16_t>(_mm_cvtsi128_si32(r) & 0xffff);
}

// Carry-less multiplication folding (Intel's "Fast CRC computation for generic polynomials using
// PCLMULQDQ"), for long frames on kX86-64. The data, read as one big polynomial, is kept reduced
// to 128 bits: a block A at distance D bits ahead of the next one becomes
// A_hi * (x^(D+64) mod G) + A_lo * (x^D mod G), which is congruent to A * x^D modulo G. At the
// end reduce() gives the CRC register, and the table finishes the last bytes. Needs n >= 16.
SYMB_CLMUL std::uint16_t crc_clmul(const std::byte* p, std::size_t n, std::uint16_t crc) {
  constexpr std::uint64_t kX128 = xpow_mod(128), kX192 = xpow_mod(192), kX256 = xpow_mod(256), kX320 = xpow_mod(320),
                          kX384 = xpow_mod(384), kX448 = xpow_mod(448), kX512 = xpow_mod(512), kX576 = xpow_mod(576);
  // The constants that move a block 128, 256, 384 or 512 bits ahead.
  const __m128i k128 = _mm_set_epi64x(kX192, kX128), k256 = _mm_set_epi64x(kX320, kX256),
                k384 = _mm_set_epi64x(kX448, kX384), k512 = _mm_set_epi64x(kX576, kX512);

  // A running CRC is the same as xoring it into the first 16 bits of the data.
  const std::uint64_t shifted = std::uint64_t{crc} << 48;
  const auto seed = static_cast<long long>(shifted);
  __m128i a0 = _mm_xor_si128(load_reversed(p), _mm_set_epi64x(seed, 0));
  std::size_t i = 16;
  if (n >= 128) {
    // Four independent lanes keep the multiplier busy while each product is still in flight
    // (eight lanes measured slower: the compiler spills them).
    __m128i a1 = load_reversed(p + 16), a2 = load_reversed(p + 32), a3 = load_reversed(p + 48);
    for (i = 64; i + 64 <= n; i += 64) {
      a0 = _mm_xor_si128(fold(a0, k512), load_reversed(p + i));
      a1 = _mm_xor_si128(fold(a1, k512), load_reversed(p + i + 16));
      a2 = _mm_xor_si128(fold(a2, k512), load_reversed(p + i + 32));
      a3 = _mm_xor_si128(fold(a3, k512), load_reversed(p + i + 48));
    }
    a0 = _mm_xor_si128(_mm_xor_si128(fold(a0, k384), fold(a1, k256)), _mm_xor_si128(fold(a2, k128), a3));
  }
  for (; i + 16 <= n; i += 16) a0 = _mm_xor_si128(fold(a0, k128), load_reversed(p + i));
  return crc_bytewise(p + i, n - i, reduce(a0));
}
#undef SYMB_CLMUL

#define SYMB_AVX512 __attribute__((target("avx512f,avx512bw,vpclmulqdq,pclmul,ssse3")))

// (Built from plain sets, loads and stores: g++ 12's AVX-512 broadcast and extract intrinsics
// trip a false -Wuninitialized inside its own headers, GCC bug 105593.)
SYMB_AVX512 inline __m512i broadcast(std::uint64_t hi, std::uint64_t lo) {
  const auto h = static_cast<long long>(hi), l = static_cast<long long>(lo);
  return _mm512_set_epi64(h, l, h, l, h, l, h, l);
}

SYMB_AVX512 inline __m512i load_reversed_512(const std::byte* p) {
  const __m512i reverse =
      _mm512_set_epi64(0x0001020304050607, 0x08090a0b0c0d0e0f, 0x0001020304050607, 0x08090a0b0c0d0e0f,
                       0x0001020304050607, 0x08090a0b0c0d0e0f, 0x0001020304050607, 0x08090a0b0c0d0e0f);
  return _mm512_shuffle_epi8(_mm512_loadu_si512(p), reverse);
}

SYMB_AVX512 inline __m512i fold_512(__m512i a, __m512i k) {
  return _mm512_xor_si512(_mm512_clmulepi64_epi128(a, k, 0x11), _mm512_clmulepi64_epi128(a, k, 0x00));
}

// The same folding, four 128-bit lanes per instruction (AVX-512 VPCLMULQDQ): about three times
// the speed of crc_clmul on a kilobyte. Lane j of a 64-byte register holds the j-th 16-byte
// block, so the last step weighs lane 0 by x^384 down to lane 3 by 1. Needs n >= 256.
SYMB_AVX512 std::uint16_t crc_avx512(const std::byte* p, std::size_t n, std::uint16_t crc) {
  constexpr std::uint64_t kX128 = xpow_mod(128), kX192 = xpow_mod(192), kX256 = xpow_mod(256), kX320 = xpow_mod(320),
                          kX384 = xpow_mod(384), kX448 = xpow_mod(448), kX512 = xpow_mod(512), kX576 = xpow_mod(576),
                          kX1024 = xpow_mod(1024), kX1088 = xpow_mod(1088), kX1536 = xpow_mod(1536),
                          kX1600 = xpow_mod(1600), kX2048 = xpow_mod(2048), kX2112 = xpow_mod(2112);
  const __m512i k512 = broadcast(kX576, kX512), k1024 = broadcast(kX1088, kX1024), k1536 = broadcast(kX1600, kX1536),
                k2048 = broadcast(kX2112, kX2048);

  const std::uint64_t shifted = std::uint64_t{crc} << 48;
  const auto seed = static_cast<long long>(shifted);
  const __m512i first = _mm512_set_epi64(0, 0, 0, 0, 0, 0, seed, 0);
  __m512i z0 = _mm512_xor_si512(load_reversed_512(p), first);
  __m512i z1 = load_reversed_512(p + 64), z2 = load_reversed_512(p + 128), z3 = load_reversed_512(p + 192);
  std::size_t i = 256;
  for (; i + 256 <= n; i += 256) {
    z0 = _mm512_xor_si512(fold_512(z0, k2048), load_reversed_512(p + i));
    z1 = _mm512_xor_si512(fold_512(z1, k2048), load_reversed_512(p + i + 64));
    z2 = _mm512_xor_si512(fold_512(z2, k2048), load_reversed_512(p + i + 128));
    z3 = _mm512_xor_si512(fold_512(z3, k2048), load_reversed_512(p + i + 192));
  }
  __m512i z = _mm512_xor_si512(_mm512_xor_si512(fold_512(z0, k1536), fold_512(z1, k1024)),
                               _mm512_xor_si512(fold_512(z2, k512), z3));
  for (; i + 64 <= n; i += 64) z = _mm512_xor_si512(fold_512(z, k512), load_reversed_512(p + i));
  alignas(64) __m128i lane[4];
  _mm512_store_si512(lane, z);
  const __m128i k128 = _mm_set_epi64x(static_cast<long long>(kX192), static_cast<long long>(kX128));
  const __m128i k256 = _mm_set_epi64x(static_cast<long long>(kX320), static_cast<long long>(kX256));
  const __m128i k384 = _mm_set_epi64x(static_cast<long long>(kX448), static_cast<long long>(kX384));
  __m128i a = _mm_xor_si128(_mm_xor_si128(fold(lane[0], k384), fold(lane[1], k256)),
                            _mm_xor_si128(fold(lane[2], k128), lane[3]));
  for (; i + 16 <= n; i += 16) a = _mm_xor_si128(fold(a, k128), load_reversed(p + i));
  return crc_bytewise(p + i, n - i, reduce(a));
}
#undef SYMB_AVX512

enum class Simd { kNone, kClmul, kAvx512 };

// What this CPU (and its OS, for the AVX-512 register state) supports; asked once.
Simd best_simd() {
  static const Simd kPath = [] {
    if (!__builtin_cpu_supports("pclmul") || !__builtin_cpu_supports("ssse3")) return Simd::kNone;
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("vpclmulqdq"))
      return Simd::kAvx512;
    return Simd::kClmul;
  }();
  return kPath;
}
#endif

// A run of up to 254 bytes. Kept opaque (noipa) on purpose: where g++ can see that bound it
// expands memcpy into `rep movsq`, whose start-up cost made it half of decoding.
#if defined(__clang__)
[[gnu::noinline]]
#else
[[gnu::noipa]]
#endif
void copy_run(std::byte* to, const std::byte* from, std::size_t n) {
  std::memcpy(to, from, n);
}

// COBS, streamed: a block is up to 254 non-zero bytes after a code byte that says how many (+1)
// and whether a zero follows. Runs are found with memchr and copied whole.
class CobsWriter {
 public:
  explicit CobsWriter(std::byte* out) : code_at_(out), w_(out + 1) {}

  void put(std::span<const std::byte> s) {
    if (s.size() < 16) {
      // Too short for memchr and memcpy calls to pay off.
      for (std::byte b : s) {
        if (b == std::byte{0}) {
          close_block();
          continue;
        }
        *w_++ = b;
        if (++run_ == 254) close_block();
      }
      return;
    }
    while (!s.empty()) {
      const std::size_t look = std::min<std::size_t>(254 - run_, s.size());
      const void* zero = std::memchr(s.data(), 0, look);
      const std::size_t k =
          zero != nullptr ? static_cast<std::size_t>(static_cast<const std::byte*>(zero) - s.data()) : look;
      std::memcpy(w_, s.data(), k);
      w_ += k;
      run_ += k;
      s = s.subspan(k);
      if (zero != nullptr) {
        close_block();
        s = s.subspan(1);
      } else if (run_ == 254) {
        close_block();
      }
    }
  }
#if defined(__x86_64__)
  // The same with AVX-512: each step copies up to 64 bytes with one masked load and store and
  // finds the first zero among them from the compare mask, with no call.
  __attribute__((target("avx512f,avx512bw"))) void put_wide(std::span<const std::byte> s) {
    // The state lives in locals: the stores go through std::byte pointers, which may alias
    // anything, so members would be reloaded from memory after every store.
    std::byte* w = w_;
    std::byte* code_at = code_at_;
    std::size_t run = run_;
    const std::byte* p = s.data();
    std::size_t left = s.size();
    const __m512i zero = _mm512_setzero_si512();
    while (left != 0) {
      const std::size_t rest = 254 - run;  // what the block still takes
      if (rest > 192 && left >= rest) {
        // The rest of a block at once, the common case of data with few zeros: four loads
        // whose zero tests do not wait on each other.
        const __mmask64 tail = (__mmask64{1} << (rest - 192)) - 1;
        const __m512i v0 = _mm512_loadu_si512(p), v1 = _mm512_loadu_si512(p + 64), v2 = _mm512_loadu_si512(p + 128),
                      v3 = _mm512_maskz_loadu_epi8(tail, p + 192);
        const __mmask64 any = _mm512_cmpeq_epi8_mask(v0, zero) | _mm512_cmpeq_epi8_mask(v1, zero) |
                              _mm512_cmpeq_epi8_mask(v2, zero) | _mm512_mask_cmpeq_epi8_mask(tail, v3, zero);
        if (any == 0) {
          _mm512_storeu_si512(w, v0);
          _mm512_storeu_si512(w + 64, v1);
          _mm512_storeu_si512(w + 128, v2);
          _mm512_mask_storeu_epi8(w + 192, tail, v3);
          w += rest;
          *code_at = std::byte{0xff};
          code_at = w++;
          run = 0;
          p += rest;
          left -= rest;
          continue;
        }
      }
      const auto n = std::min<std::size_t>({64, 254 - run, left});
      const __mmask64 take = n == 64 ? ~__mmask64{0} : (__mmask64{1} << n) - 1;
      const __m512i v = _mm512_maskz_loadu_epi8(take, p);
      _mm512_mask_storeu_epi8(w, take, v);
      const __mmask64 zeros = _mm512_mask_cmpeq_epi8_mask(take, v, zero);
      // Up to the first zero (or all n bytes); the zero's slot becomes the next code byte.
      const auto k = zeros == 0 ? n : static_cast<std::size_t>(__builtin_ctzll(zeros));
      w += k;
      run += k;
      p += k;
      left -= k;
      if (zeros != 0 || run == 254) {
        *code_at = static_cast<std::byte>(run + 1);
        code_at = w++;
        run = 0;
        if (zeros != 0) {
          ++p;
          --left;
        }
      }
    }
    w_ = w;
    code_at_ = code_at;
    run_ = run;
  }
#endif
  // Closes the last block; returns one past the last byte written.
  std::byte* end() {
    *code_at_ = static_cast<std::byte>(run_ + 1);
    return w_;
  }

 private:
  void close_block() {
    *code_at_ = static_cast<std::byte>(run_ + 1);
    code_at_ = w_++;
    run_ = 0;
  }

  std::byte* code_at_;
  std::byte* w_;
  std::size_t run_ = 0;
};

}  // namespace

std::uint16_t crc16_ccitt(std::span<const std::byte> data, std::uint16_t crc) {
#if defined(__x86_64__)
  // Below 64 bytes the table wins: the folding's setup and final reduction cost more than
  // they save.
  if (data.size() >= 64) {
    const Simd path = best_simd();
    if (path == Simd::kAvx512 && data.size() >= 256) return crc_avx512(data.data(), data.size(), crc);
    if (path != Simd::kNone) return crc_clmul(data.data(), data.size(), crc);
  }
#endif
  return crc_bytewise(data.data(), data.size(), crc);
}

std::size_t encode_frame(std::span<const std::byte> payload, std::span<std::byte> out) {
  if (out.size() < max_encoded_size(payload.size())) return 0;
  const std::byte version{kFrameVersion};
  const std::uint16_t crc = crc16_ccitt(payload, crc_bytewise(&version, 1, 0xFFFF));
  const std::byte tail[2] = {std::byte(crc >> 8), std::byte(crc & 0xff)};

  std::byte* const base = out.data();
  base[0] = std::byte{0};
  CobsWriter cobs(base + 1);
  cobs.put({&version, 1});
#if defined(__x86_64__)
  if (payload.size() >= 64 && best_simd() == Simd::kAvx512)
    cobs.put_wide(payload);
  else
    cobs.put(payload);
#else
  cobs.put(payload);
#endif
  cobs.put(tail);
  std::byte* end = cobs.end();
  *end++ = std::byte{0};
  return static_cast<std::size_t>(end - base);
}

void encode_frame(std::span<const std::byte> payload, std::vector<std::byte>& out) {
  // Room is made up front (zero-filled: the price of std::vector), then trimmed.
  const std::size_t start = out.size();
  out.resize(start + max_encoded_size(payload.size()));
  const std::size_t n = encode_frame(payload, std::span<std::byte>(out.data() + start, out.size() - start));
  out.resize(start + n);
}

std::vector<std::byte> encode_frame(std::span<const std::byte> payload) {
  std::vector<std::byte> out;
  out.reserve(max_encoded_size(payload.size()));
  encode_frame(payload, out);
  return out;
}

FrameDecoder::FrameDecoder(std::size_t max_payload)
    : max_payload_(max_payload), max_encoded_(max_encoded_size(max_payload) - 2) {
  encoded_.reserve(max_encoded_);
  // A frame never decodes to more bytes than it had encoded.
  decoded_.resize(max_encoded_);
}

void FrameDecoder::reset() {
  encoded_.clear();
  overflow_ = false;
}

void FrameDecoder::append(std::span<const std::byte> part) {
  if (overflow_) return;
  if (part.size() > max_encoded_ - encoded_.size()) {
    // Too long to be a frame: remember that, not the bytes, so garbage cannot grow memory.
    overflow_ = true;
    encoded_.clear();
    return;
  }
  encoded_.insert(encoded_.end(), part.begin(), part.end());
}

bool FrameDecoder::finish(std::span<const std::byte> encoded) {
  if (overflow_ || encoded.size() > max_encoded_) {
    ++stats_.oversized;
    reset();
    return false;
  }
  if (encoded.empty()) return false;  // back-to-back delimiters are idle line, not a frame
  std::byte* const out = decoded_.data();
  std::size_t o = 0;
  bool ok = true;
  for (std::size_t i = 0; i < encoded.size();) {
    const auto code = static_cast<std::size_t>(encoded[i]);
    if (code == 0 || code > encoded.size() - i) {
      ok = false;
      break;
    }
    if (code <= 16) {
      for (std::size_t k = 1; k < code; ++k) out[o + k - 1] = encoded[i + k];  // short: no call
    } else {
      copy_run(out + o, encoded.data() + i + 1, code - 1);
    }
    o += code - 1;
    i += code;
    if (code != 0xff && i < encoded.size()) out[o++] = std::byte{0};
  }
  decoded_size_ = o;
  encoded_.clear();
  if (!ok) {
    ++stats_.bad_encoding;
    return false;
  }
  if (o < 3) {
    ++stats_.truncated;
    return false;
  }
  if (o - 3 > max_payload_) {
    ++stats_.oversized;
    return false;
  }
  const std::size_t body = o - 2;
  const auto crc =
      static_cast<std::uint16_t>((static_cast<unsigned>(out[body]) << 8) | static_cast<unsigned>(out[body + 1]));
  if (crc16_ccitt({out, body}) != crc) {
    ++stats_.crc_errors;
    return false;
  }
  if (static_cast<std::uint8_t>(out[0]) != kFrameVersion) {
    ++stats_.bad_version;
    return false;
  }
  ++stats_.frames;
  return true;
}

}  // namespace symb::io
