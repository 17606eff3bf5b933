// XCDR1 ("plain CDR", as ROS 2 and idlc's @final types) straight between cairn's C++ message structs and
// serialized bytes. Used by the code msgs/cmake/idl2cpp.py generates; no DDS header here.
//
// Layout rules (OMG DDS-XTypes 1.3, 7.4.3 "XCDR1 Serialization"): primitives are aligned to their size
// (8-byte types to 8), relative to the first byte after the 4-byte encapsulation header; strings are a
// uint32 length that counts the terminating NUL, then the bytes and the NUL; sequences are a uint32
// element count, then the elements; arrays are their elements; @final structs are their fields in order.
//
// Reading validates everything against the buffer (garbage from the network must never crash or make us
// allocate more than the buffer could describe): every length is checked against the bytes left before
// anything is allocated, strings must end in NUL, booleans must be 0 or 1, bounded sequences must respect
// their bound. A violation throws CdrError naming the offset.
#ifndef CAIRN_MSGS_CDR_HPP
#define CAIRN_MSGS_CDR_HPP

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace cairn::msgs {

/// Malformed or truncated CDR input.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace gen {

template <class T>
constexpr bool cdr_prim_v = std::is_arithmetic_v<T>;

/// Counts the bytes a message serializes to (first pass: the serialized sample is allocated once).
struct CdrSizer {
  std::size_t pos = 0;
  void align(std::size_t a) { pos = (pos + a - 1) & ~(a - 1); }
  template <class T>
  void prim(const T&) {
    align(sizeof(T));
    pos += sizeof(T);
  }
  template <class T>
  void prims(const T*, std::size_t n) {
    if (n == 0) return;
    align(sizeof(T));
    pos += n * sizeof(T);
  }
  void bytes(const char*, std::size_t n) { pos += n; }
};

/// Writes into a buffer sized by CdrSizer (padding bytes are written as zeros).
struct CdrWriter {
  unsigned char* base;
  std::size_t pos = 0;
  void align(std::size_t a) {
    const std::size_t to = (pos + a - 1) & ~(a - 1);
    while (pos < to) base[pos++] = 0;
  }
  template <class T>
  void prim(const T& v) {
    align(sizeof(T));
    std::memcpy(base + pos, &v, sizeof(T));  // cairn runs on little-endian hosts (static_assert below)
    pos += sizeof(T);
  }
  template <class T>
  void prims(const T* p, std::size_t n) {
    if (n == 0) return;
    align(sizeof(T));
    std::memcpy(base + pos, p, n * sizeof(T));
    pos += n * sizeof(T);
  }
  void bytes(const char* p, std::size_t n) {
    std::memcpy(base + pos, p, n);
    pos += n;
  }
};

static_assert(std::endian::native == std::endian::little, "cairn's CDR writer emits the host byte order as CDR_LE");

/// Reads and validates; `swap` for big-endian (CDR_BE) input.
struct CdrReader {
  const unsigned char* base;
  std::size_t size;
  std::size_t pos = 0;
  bool swap = false;

  [[noreturn]] void fail(const char* what) const {
    throw CdrError("malformed CDR at payload offset " + std::to_string(pos) + " of " + std::to_string(size) + ": " +
                   what);
  }
  std::size_t left() const { return size - pos; }
  void align(std::size_t a) {
    const std::size_t to = (pos + a - 1) & ~(a - 1);
    if (to > size) fail("truncated (padding)");
    pos = to;
  }
  template <class T>
  static T byteswap(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  template <class T>
  void prim(T& v) {
    align(sizeof(T));
    if (left() < sizeof(T)) fail("truncated");
    std::memcpy(&v, base + pos, sizeof(T));
    if constexpr (sizeof(T) > 1) {
      if (swap) v = byteswap(v);
    }
    pos += sizeof(T);
  }
  uint32_t length() {
    uint32_t n;
    prim(n);
    return n;
  }
};

// ---------- primitives, strings, sequences, arrays (structs: generated, found by ADL on Adl) ----------
template <class O, class T>
  requires cdr_prim_v<T>
void cdr_field(O& o, const T& v, unsigned = 0) {
  if constexpr (std::is_same_v<T, bool>) {
    o.prim(static_cast<uint8_t>(v ? 1 : 0));
  } else {
    o.prim(v);
  }
}

template <class O>
void cdr_field(O& o, const std::string& s, unsigned = 0) {
  if (s.size() >= std::numeric_limits<uint32_t>::max()) throw std::length_error("string too long for CDR");
  o.prim(static_cast<uint32_t>(s.size() + 1));
  o.bytes(s.c_str(), s.size() + 1);  // with the terminating NUL
}

inline void check_bound(std::size_t n, unsigned bound) {
  if (bound != 0 && n > bound) {
    throw std::length_error("sequence of " + std::to_string(n) + " elements exceeds its bound " + std::to_string(bound));
  }
  if (n > std::numeric_limits<uint32_t>::max()) throw std::length_error("sequence too long for CDR");
}

template <class O, class T>
void cdr_field(O& o, const std::vector<T>& v, unsigned bound = 0) {
  check_bound(v.size(), bound);
  o.prim(static_cast<uint32_t>(v.size()));
  if constexpr (cdr_prim_v<T> && !std::is_same_v<T, bool>) {
    o.prims(v.data(), v.size());
  } else {
    for (const auto& e : v) cdr_field(o, e, 0u);
  }
}

template <class O, class T, std::size_t N>
void cdr_field(O& o, const std::array<T, N>& a, unsigned = 0) {
  if constexpr (cdr_prim_v<T> && !std::is_same_v<T, bool>) {
    o.prims(a.data(), N);
  } else {
    for (const auto& e : a) cdr_field(o, e, 0u);
  }
}

// ---------- reading ----------
template <class T>
  requires cdr_prim_v<T>
void cdr_get(CdrReader& r, T& v, unsigned = 0) {
  if constexpr (std::is_same_v<T, bool>) {
    uint8_t b;
    r.prim(b);
    if (b > 1) r.fail("boolean is neither 0 nor 1");
    v = b != 0;
  } else {
    r.prim(v);
  }
}

inline void cdr_get(CdrReader& r, std::string& s, unsigned = 0) {
  const uint32_t n = r.length();
  if (n == 0) r.fail("string length 0 (CDR strings count their NUL)");
  if (n > r.left()) r.fail("string longer than the sample");
  const char* p = reinterpret_cast<const char*>(r.base + r.pos);
  if (p[n - 1] != 0) r.fail("string not NUL-terminated");
  s.assign(p, n - 1);
  r.pos += n;
}

template <class T>
void swap_all(T* p, std::size_t n) {
  if constexpr (sizeof(T) > 1) {
    for (std::size_t i = 0; i < n; ++i) p[i] = CdrReader::byteswap(p[i]);
  }
}

template <class T>
void cdr_get(CdrReader& r, std::vector<T>& v, unsigned bound = 0) {
  const uint32_t n = r.length();
  if (bound != 0 && n > bound) r.fail("sequence longer than its bound");
  if constexpr (cdr_prim_v<T> && !std::is_same_v<T, bool>) {
    if (n == 0) {
      v.clear();
      return;
    }
    r.align(sizeof(T));
    if (n > r.left() / sizeof(T)) r.fail("sequence longer than the sample");
    const T* first = reinterpret_cast<const T*>(r.base + r.pos);  // assign() copies bytewise-safe
    if (reinterpret_cast<uintptr_t>(first) % alignof(T) == 0) {
      v.assign(first, first + n);
    } else {
      v.resize(n);
      std::memcpy(v.data(), r.base + r.pos, std::size_t(n) * sizeof(T));
    }
    if (r.swap) swap_all(v.data(), n);
    r.pos += std::size_t(n) * sizeof(T);
  } else {
    // every element of a cairn type takes at least one byte (idl2cpp rejects empty structs)
    if (n > r.left()) r.fail("sequence longer than the sample");
    v.resize(n);
    for (auto& e : v) cdr_get(r, e, 0u);
  }
}

/// sequence<boolean> (std::vector<uint8_t> in C++: std::vector<bool> is not contiguous); elements 0 or 1.
inline void cdr_get_bools(CdrReader& r, std::vector<uint8_t>& v, unsigned bound = 0) {
  cdr_get(r, v, bound);
  for (uint8_t b : v) {
    if (b > 1) r.fail("boolean is neither 0 nor 1");
  }
}

template <class T, std::size_t N>
void cdr_get(CdrReader& r, std::array<T, N>& a, unsigned = 0) {
  if constexpr (cdr_prim_v<T> && !std::is_same_v<T, bool>) {
    if (N == 0) return;
    r.align(sizeof(T));
    if (N > r.left() / sizeof(T)) r.fail("array longer than the sample");
    std::memcpy(a.data(), r.base + r.pos, N * sizeof(T));
    if (r.swap) swap_all(a.data(), N);
    r.pos += N * sizeof(T);
  } else {
    for (auto& e : a) cdr_get(r, e, 0u);
  }
}

}  // namespace gen
}  // namespace cairn::msgs

#endif  // CAIRN_MSGS_CDR_HPP
