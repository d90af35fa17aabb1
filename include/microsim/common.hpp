// Shared vocabulary of microsim: vectors, errors, estimates and counter-based randomness.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace microsim {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
// JSON records keep their fields in the order they are written (readable files and CSV columns).
using Json = nlohmann::ordered_json;

constexpr double kPi = 3.14159265358979323846;

// A usage error: bad option value, unknown surface kind, missing file... (CLI exit code 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A usage error naming parameters of the library (theta_i, rays, height_scale), never a front
// end's spelling of them: its message is a template in which "{name}" is the parameter `name`
// and "{{" a literal "{". Each front end spells the parameters when it prints the message
// (spell_parameters): the command line as its options (--theta-i), Python as its keywords.
struct ParameterError : UsageError {
  using UsageError::UsageError;
};
// Turns a parameter's name into a front end's word for it.
using ParameterSpeller = std::function<std::string(std::string_view name)>;
// `message` with every "{name}" (name: lower-case letters, digits, '_') replaced by
// speller(name) and every "{{" by "{"; any other brace is kept as it is.
std::string spell_parameters(std::string_view message, const ParameterSpeller& speller);
// The text of `e` as a front end prints it: a ParameterError spelled, another error as it is.
std::string spelled_message(const UsageError& e, const ParameterSpeller& speller);
// The parameter `name` as a ParameterError's message names it: "{name}".
std::string placeholder(std::string_view name);
// `text` (a path, a value given by the user) inside a ParameterError's message: its braces are
// doubled, so that no front end reads a placeholder in it.
std::string literal_text(std::string_view text);
// The message of `e` as a part of a ParameterError's message (to say where it arose): a
// ParameterError's own template, another error's text as literal text.
std::string message_template(const UsageError& e);

// A failure while running on valid input (CLI exit code 1).
struct RuntimeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A Monte Carlo estimate with its standard error and the number of samples behind it.
struct Estimate {
  double mean = 0.0;
  double stderr_ = 0.0;
  std::uint64_t n = 0;
};

// Binomial proportion k/n with standard error sqrt(p(1-p)/n). For stratified sampling this
// is an upper bound on the true standard error (stratification never increases variance).
Estimate binomial_estimate(std::uint64_t k, std::uint64_t n);

// Direction from spherical angles (radians) about the macrosurface normal +z.
inline Vec3 direction_from_angles(double theta, double phi) {
  return Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
}
inline double theta_of(const Vec3& d) { return std::acos(std::clamp(d.z(), -1.0, 1.0)); }
inline double phi_of(const Vec3& d) {
  double p = std::atan2(d.y(), d.x());
  return p < 0 ? p + 2 * kPi : p;
}
inline double deg(double rad) { return rad * 180.0 / kPi; }
inline double rad(double deg) { return deg * kPi / 180.0; }

// Counter-based random numbers: the value depends only on (seed, stream, index), so results do
// not depend on thread count or scheduling. Mixing by the splitmix64 finalizer.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
class CounterRng {
 public:
  CounterRng(std::uint64_t seed, std::uint64_t stream, std::uint64_t index)
      : state_(mix64(key(seed, stream) ^ index)) {}
  // The part of the state that depends on (seed, stream) only: loops over many indices of one
  // stream compute it once and construct CounterRng(Keyed{}, key, index), the same generator.
  static std::uint64_t key(std::uint64_t seed, std::uint64_t stream) {
    return mix64(seed ^ mix64(stream + 0x51ED270B27E3A5F1ull));
  }
  struct Keyed {};
  CounterRng(Keyed, std::uint64_t key, std::uint64_t index) : state_(mix64(key ^ index)) {}
  std::uint64_t next_u64() { return mix64(state_ += 0x9E3779B97F4A7C15ull); }
  // Uniform in [0, 1), 53 random bits.
  double uniform() { return (next_u64() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  std::uint64_t state_;
};

// Morton (Z-order) decoding of a 2D index: rays are issued along this curve so that
// consecutive rays are spatially close (coherent BVH traversal).
inline std::uint32_t compact_bits(std::uint64_t x) {
  x &= 0x5555555555555555ull;
  x = (x | (x >> 1)) & 0x3333333333333333ull;
  x = (x | (x >> 2)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x >> 4)) & 0x00FF00FF00FF00FFull;
  x = (x | (x >> 8)) & 0x0000FFFF0000FFFFull;
  x = (x | (x >> 16)) & 0x00000000FFFFFFFFull;
  return static_cast<std::uint32_t>(x);
}
inline void morton_decode(std::uint64_t code, std::uint32_t& x, std::uint32_t& y) {
  x = compact_bits(code);
  y = compact_bits(code >> 1);
}

// x (< 2^32) spread to the even bits of a word: the inverse of compact_bits.
inline std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0xFFFFFFFFull;
  x = (x | (x << 16)) & 0x0000FFFF0000FFFFull;
  x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
  x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | (x << 2)) & 0x3333333333333333ull;
  x = (x | (x << 1)) & 0x5555555555555555ull;
  return x;
}
// The Morton code of (x, y): the inverse of morton_decode.
inline std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y) { return spread_bits(x) | (spread_bits(y) << 1); }

}  // namespace microsim
