// Helpers used only by the generated type-support sources (they include idlc's C headers).
#ifndef CAIRN_MSGS_TYPE_SUPPORT_IMPL_HPP
#define CAIRN_MSGS_TYPE_SUPPORT_IMPL_HPP

#include <array>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <limits>
#include <new>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "cairn/msgs/cdr.hpp"
#include "cairn/msgs/type_support.hpp"
#include "dds/dds.h"

namespace cairn::msgs::gen {

template <class T>
constexpr bool is_prim_v = std::is_arithmetic_v<T>;

// ---------- C++ -> C (borrowing) ----------
template <class T, class C>
  requires is_prim_v<T>
void conv_to_c(const T& m, C& c, Scratch&, const char*, unsigned) {
  c = static_cast<C>(m);
}

inline void conv_to_c(const std::string& m, char*& c, Scratch&, const char*, unsigned) {
  c = const_cast<char*>(m.c_str());
}

template <class M, class C>
  requires std::is_class_v<M> && (!std::is_same_v<M, std::string>)
void conv_to_c(const M& m, C& c, Scratch& s, const char*, unsigned) {
  to_c(m, c, s, Adl{});
}

template <class T, std::size_t N, class C>
void conv_to_c(const std::array<T, N>& m, C (&c)[N], Scratch& s, const char* where, unsigned) {
  for (std::size_t i = 0; i < N; ++i) conv_to_c(m[i], c[i], s, where, 0);
}

template <class T, class Seq>
  requires requires(Seq q) { q._buffer; q._length; }
void conv_to_c(const std::vector<T>& m, Seq& c, Scratch& s, const char* where, unsigned bound) {
  using CE = std::remove_pointer_t<decltype(c._buffer)>;
  if (bound != 0 && m.size() > bound) {
    throw std::length_error(std::string(where) + ": sequence of " + std::to_string(m.size()) +
                            " elements exceeds its bound " + std::to_string(bound));
  }
  if (m.size() > std::numeric_limits<uint32_t>::max()) {
    throw std::length_error(std::string(where) + ": sequence too long for CDR");
  }
  c._length = c._maximum = static_cast<uint32_t>(m.size());
  c._release = false;
  if (m.empty()) {
    c._buffer = nullptr;
    return;
  }
  if constexpr (is_prim_v<T> && is_prim_v<CE> && sizeof(T) == sizeof(CE)) {
    c._buffer = reinterpret_cast<CE*>(const_cast<T*>(m.data()));  // borrow: zero copies
  } else {
    CE* buf = static_cast<CE*>(s.alloc(sizeof(CE) * m.size()));
    for (std::size_t i = 0; i < m.size(); ++i) conv_to_c(m[i], buf[i], s, where, 0);
    c._buffer = buf;
  }
}

// ---------- C -> C++ (copying) ----------
template <class C, class T>
  requires is_prim_v<T>
void conv_from_c(const C& c, T& m) {
  m = static_cast<T>(c);
}

inline void conv_from_c(char* const& c, std::string& m) { m.assign(c ? c : ""); }

template <class C, class M>
  requires std::is_class_v<M> && (!std::is_same_v<M, std::string>) && (!requires(C q) { q._buffer; })
void conv_from_c(const C& c, M& m) {
  from_c(c, m, Adl{});
}

template <class C, class T, std::size_t N>
void conv_from_c(const C (&c)[N], std::array<T, N>& m) {
  for (std::size_t i = 0; i < N; ++i) conv_from_c(c[i], m[i]);
}

template <class Seq, class T>
  requires requires(Seq q) { q._buffer; q._length; }
void conv_from_c(const Seq& c, std::vector<T>& m) {
  using CE = std::remove_pointer_t<decltype(c._buffer)>;
  if constexpr (is_prim_v<T> && is_prim_v<CE> && sizeof(T) == sizeof(CE)) {
    const T* b = reinterpret_cast<const T*>(c._buffer);
    m.assign(b, b + c._length);
  } else {
    m.resize(c._length);
    for (uint32_t i = 0; i < c._length; ++i) conv_from_c(c._buffer[i], m[i]);
  }
}

// ---------- printing ----------
void print_indent(std::ostream& o, int indent);
void print_scalar(std::ostream& o, double v);
void print_scalar(std::ostream& o, float v);
void print_string(std::ostream& o, const std::string& s);

template <class T>
void print_value(std::ostream& o, const T& v) {
  if constexpr (std::is_same_v<T, std::string>) {
    print_string(o, v);
  } else if constexpr (std::is_same_v<T, bool>) {
    o << (v ? "true" : "false");
  } else if constexpr (std::is_floating_point_v<T>) {
    print_scalar(o, v);
  } else if constexpr (sizeof(T) == 1) {
    o << static_cast<int>(v);
  } else {
    o << v;
  }
}

// Elements of a list of numbers or strings printed before "... (N in all)"; 0 = all (to_text's max_elements).
std::size_t print_max_elements();

template <class Range>
void print_list(std::ostream& o, int indent, const char* name, const Range& r) {
  using T = std::decay_t<decltype(*std::begin(r))>;
  print_indent(o, indent);
  o << name << ":";
  if constexpr (is_prim_v<T> || std::is_same_v<T, std::string>) {
    o << " [";
    std::size_t i = 0;
    const std::size_t limit = print_max_elements();
    for (const auto& v : r) {
      if (limit != 0 && i == limit) {
        o << ", ... (" << std::size(r) << " in all)";
        break;
      }
      if (i++) o << ", ";
      print_value(o, v);
    }
    o << "]\n";
  } else {
    if (std::size(r) == 0) {
      o << " []\n";
      return;
    }
    o << "\n";
    for (const auto& v : r) {
      print_indent(o, indent);
      o << "-\n";
      print(v, o, indent + 2, Adl{});
    }
  }
}

template <class T>
void print_field(std::ostream& o, int indent, const char* name, const T& v) {
  if constexpr (is_prim_v<T> || std::is_same_v<T, std::string>) {
    print_indent(o, indent);
    o << name << ": ";
    print_value(o, v);
    o << "\n";
  } else {
    print_indent(o, indent);
    o << name << ":\n";
    print(v, o, indent + 2, Adl{});
  }
}

template <class T>
void print_field(std::ostream& o, int indent, const char* name, const std::vector<T>& v) {
  print_list(o, indent, name, v);
}

template <class T, std::size_t N>
void print_field(std::ostream& o, int indent, const char* name, const std::array<T, N>& v) {
  print_list(o, indent, name, v);
}

}  // namespace cairn::msgs::gen

namespace cairn::msgs {

template <class T, class C>
TypeSupport make_type_support(const char* dds_name, const char* ros_name, const dds_topic_descriptor_t* desc) {
  TypeSupport ts{};
  ts.dds_type_name = dds_name;
  ts.ros_type_name = ros_name;
  ts.descriptor = desc;
  ts.c_size = sizeof(C);
  ts.to_c = [](const void* cpp, void* c, Scratch& s) {
    to_c(*static_cast<const T*>(cpp), *static_cast<C*>(c), s, gen::Adl{});
  };
  ts.from_c = [](const void* c, void* cpp) { from_c(*static_cast<const C*>(c), *static_cast<T*>(cpp), gen::Adl{}); };
  ts.create = []() -> void* { return new T(); };
  ts.destroy = [](void* p) { delete static_cast<T*>(p); };
  ts.print = [](const void* cpp, std::ostream& o) { print(*static_cast<const T*>(cpp), o, 0, gen::Adl{}); };
  ts.cpp_size = sizeof(T);
  ts.construct = [](void* at) { new (at) T(); };
  ts.destruct = [](void* at) { static_cast<T*>(at)->~T(); };
  ts.cdr_size = [](const void* cpp) -> std::size_t {
    gen::CdrSizer s;
    cdr_field(s, *static_cast<const T*>(cpp), 0u);
    return s.pos;
  };
  ts.cdr_write = [](const void* cpp, unsigned char* out) {
    gen::CdrWriter w{out};
    cdr_field(w, *static_cast<const T*>(cpp), 0u);
  };
  ts.cdr_read = [](const unsigned char* in, std::size_t n, bool big_endian, void* cpp) {
    gen::CdrReader r{in, n, 0, big_endian};
    cdr_get(r, *static_cast<T*>(cpp), 0u);
  };
  return ts;
}

}  // namespace cairn::msgs

#endif  // CAIRN_MSGS_TYPE_SUPPORT_IMPL_HPP
