// Tallies declared once. A tally struct lists its fields in one static visitor,
//
//   template <class F> static constexpr void for_each_field(F&& f) {
//     f("rays", &TraceCounters::rays);
//     f("border_crossings", &TraceCounters::border_crossings);
//     ...
//   }
//
// and everything that must touch every field is derived from that list here: the sum of two
// tallies, their size and order as values exchanged between processes (shards, MPI ranks:
// measure/shards.hpp; FieldRows there makes one row per unit of a declared tally: the spectral
// BSDF's SpectralTally, the polarized BSDF's MuellerUnit), and their fields in a record. A field added to the declaration is then
// summed, exchanged and recorded everywhere at once; one missing from it is missing everywhere
// (and visibly so in the record), never silently dropped by one hand-written copy.
//
// Field types: std::uint64_t and std::vector<std::uint64_t> (exchanged as integers), double and
// std::vector<double> (exchanged as reals), or another declared struct (nested). A struct may
// declare more than one group of fields (a policy type with a static `each(f)`, passed as the
// second template argument); by default the group is T::for_each_field.
#pragma once
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "microsim/common.hpp"

namespace microsim {

// The group of fields a struct declares in T::for_each_field.
template <class T>
struct AllFields {
  template <class F>
  static constexpr void each(F&& f) {
    T::for_each_field(std::forward<F>(f));
  }
};

namespace tally_detail {
struct Probe {
  template <class M>
  constexpr void operator()(const char*, M) const {}
};
template <class T, class = void>
struct is_declared : std::false_type {};
template <class T>
struct is_declared<T, std::void_t<decltype(T::for_each_field(Probe{}))>> : std::true_type {};
}  // namespace tally_detail

// True for a struct that declares its fields (T::for_each_field).
template <class T>
constexpr bool is_declared_tally = tally_detail::is_declared<std::remove_const_t<T>>::value;

// Calls f(name, t.*member) for every field of the group D of t (t may be const).
template <class D, class T, class F>
void visit_fields(T& t, F&& f) {
  D::each([&](const char* name, auto member) { f(name, t.*member); });
}

// Number of integer fields of a struct made of std::uint64_t fields and nested declared structs
// (a fixed-size tally such as TraceCounters), at compile time.
template <class T, class D = AllFields<T>>
constexpr std::size_t scalar_field_count() {
  std::size_t n = 0;
  D::each([&n](const char*, auto member) {
    using M = std::remove_reference_t<decltype(std::declval<T&>().*member)>;
    if constexpr (is_declared_tally<M>) n += scalar_field_count<M>();
    else {
      static_assert(std::is_same_v<M, std::uint64_t>, "a fixed-size tally holds integers only");
      ++n;
    }
  });
  return n;
}

namespace tally_detail {
inline void add(std::uint64_t& a, std::uint64_t b) { a += b; }
inline void add(double& a, double b) { a += b; }
template <class X>
void add(std::vector<X>& a, const std::vector<X>& b) {
  if (a.empty()) {
    a = b;
    return;
  }
  for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) a[k] += b[k];
}
template <class T, std::enable_if_t<is_declared_tally<T>, int> = 0>
void add(T& a, const T& b);

// Writes the fields in declaration order: integers to `counts`, reals to `reals`.
struct Writer {
  std::uint64_t* counts;
  double* reals;
  void operator()(const char*, std::uint64_t v) { *counts++ = v; }
  void operator()(const char*, double v) { *reals++ = v; }
  template <class X>
  void operator()(const char*, const std::vector<X>& v) {
    for (const X& x : v) (*this)(nullptr, x);
  }
  template <class T, std::enable_if_t<is_declared_tally<T>, int> = 0>
  void operator()(const char*, const T& t) {
    visit_fields<AllFields<T>>(t, *this);
  }
};
// Reads them back in the same order (vectors keep their size).
struct Reader {
  const std::uint64_t* counts;
  const double* reals;
  void operator()(const char*, std::uint64_t& v) { v = *counts++; }
  void operator()(const char*, double& v) { v = *reals++; }
  template <class X>
  void operator()(const char*, std::vector<X>& v) {
    for (X& x : v) (*this)(nullptr, x);
  }
  template <class T, std::enable_if_t<is_declared_tally<T>, int> = 0>
  void operator()(const char*, T& t) {
    visit_fields<AllFields<T>>(t, *this);
  }
};
// Counts the integers and reals Writer writes.
struct Sizer {
  std::size_t counts = 0, reals = 0;
  void operator()(const char*, std::uint64_t) { ++counts; }
  void operator()(const char*, double) { ++reals; }
  template <class X>
  void operator()(const char*, const std::vector<X>& v) {
    (std::is_same_v<X, double> ? reals : counts) += v.size();
  }
  template <class T, std::enable_if_t<is_declared_tally<T>, int> = 0>
  void operator()(const char*, const T& t) {
    visit_fields<AllFields<T>>(t, *this);
  }
};
// The fields as a JSON object (vectors as arrays, nested structs as objects).
struct ToJson {
  Json& out;
  template <class X>
  void operator()(const char* name, const X& v) {
    if constexpr (is_declared_tally<X>) {
      Json sub = Json::object();
      ToJson inner{sub};
      visit_fields<AllFields<X>>(v, inner);
      out[name] = std::move(sub);
    } else {
      out[name] = v;
    }
  }
};
}  // namespace tally_detail

// a += b, field by field (vectors element by element; an empty vector of a takes b's).
template <class T, class D = AllFields<T>>
void add_fields(T& a, const T& b) {
  D::each([&](const char*, auto member) { tally_detail::add(a.*member, b.*member); });
}

// Number of integers and reals of t's fields (vectors at their current size).
struct FieldSizes {
  std::size_t counts = 0, reals = 0;
};
template <class T, class D = AllFields<T>>
FieldSizes field_sizes(const T& t) {
  tally_detail::Sizer s;
  visit_fields<D>(t, s);
  return {s.counts, s.reals};
}

// Writes t's fields in declaration order; returns the ends of what was written.
template <class T, class D = AllFields<T>>
std::pair<std::uint64_t*, double*> pack_fields(const T& t, std::uint64_t* counts, double* reals = nullptr) {
  tally_detail::Writer w{counts, reals};
  visit_fields<D>(t, w);
  return {w.counts, w.reals};
}

// Reads t's fields back from what pack_fields wrote (vectors must have their size already).
template <class T, class D = AllFields<T>>
std::pair<const std::uint64_t*, const double*> unpack_fields(T& t, const std::uint64_t* counts,
                                                             const double* reals = nullptr) {
  tally_detail::Reader r{counts, reals};
  visit_fields<D>(t, r);
  return {r.counts, r.reals};
}

// The fields as a JSON object, named as declared.
template <class T, class D = AllFields<T>>
Json fields_json(const T& t) {
  Json out = Json::object();
  tally_detail::ToJson w{out};
  visit_fields<D>(t, w);
  return out;
}

namespace tally_detail {
template <class T, std::enable_if_t<is_declared_tally<T>, int>>
void add(T& a, const T& b) {
  add_fields(a, b);
}
}  // namespace tally_detail

}  // namespace microsim
