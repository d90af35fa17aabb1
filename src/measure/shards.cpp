#include "microsim/measure/shards.hpp"
#include "microsim/io/checks.hpp"
#include "microsim/version.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>

namespace microsim {

UnitRange shard_range(std::uint64_t units, int k, int n) {
  // 128-bit products: units * n never overflows.
  const auto at = [&](int i) {
    return static_cast<std::uint64_t>(static_cast<unsigned __int128>(units) * static_cast<unsigned>(i) /
                                      static_cast<unsigned>(n));
  };
  return {at(k), at(k + 1)};
}

Tallies::Tallies(std::string kind_, std::uint64_t units_, UnitRange covered_, std::size_t rc,
                 std::size_t rr, std::size_t tc, std::size_t tr)
    : kind(std::move(kind_)), units(units_), covered(covered_), row_counts(rc), row_reals(rr),
      counts(units_ * rc, 0), reals(units_ * rr, 0.0), tail_counts(tc, 0), tail_reals(tr, 0.0) {}

ShardRecorder::ShardRecorder(int k, int n) : k_(k), n_(n) {
  if (!(n >= 1 && k >= 1 && k <= n)) throw ParameterError("{shard} must be K/N with 1 <= K <= N");
}

std::string shard_path(const std::string& output, int k, int n) {
  return output + ".shard-" + std::to_string(k) + "-of-" + std::to_string(n) + ".json";
}

std::pair<int, int> parse_shard(const std::string& text) {
  const auto bad = [&] {
    return ParameterError("{shard} must be K/N with integers 1 <= K <= N <= 4096 (got '" + literal_text(text) + "')");
  };
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw bad();
  const auto number = [&](const std::string& s) {
    if (s.empty() || s.size() > 4 || s.find_first_not_of("0123456789") != std::string::npos) throw bad();
    return std::stoi(s);
  };
  const int k = number(text.substr(0, slash)), n = number(text.substr(slash + 1));
  if (!(n >= 1 && n <= 4096 && k >= 1 && k <= n)) throw bad();
  return {k, n};
}

namespace {
std::string describe(const Tallies& t) {
  return t.kind + " (" + std::to_string(t.units) + " units, " + std::to_string(t.values()) + " values)";
}
bool same_layout(const Tallies& a, const Tallies& b) {
  return a.kind == b.kind && a.units == b.units && a.row_counts == b.row_counts &&
         a.row_reals == b.row_reals && a.tail_counts.size() == b.tail_counts.size() &&
         a.tail_reals.size() == b.tail_reals.size();
}
}  // namespace

void TallyReplay::exchange(Tallies& t) {
  if (next_ >= entries_.size())
    throw RuntimeFailure("the merged parts hold " + std::to_string(entries_.size()) +
                         " estimator calls, the command made more");
  Tallies& e = entries_[next_];
  if (!same_layout(e, t))
    throw RuntimeFailure("estimator call " + std::to_string(next_ + 1) + " of the command is " +
                         describe(t) + ", the parts hold " + describe(e));
  t = std::move(e);
  ++next_;
}

void TallyReplay::finish() const {
  if (next_ != entries_.size())
    throw RuntimeFailure("the merged parts hold " + std::to_string(entries_.size()) +
                         " estimator calls, the command made " + std::to_string(next_));
}

// --- identity -------------------------------------------------------------------------------

std::string file_hash(const std::string& path, std::uint64_t* bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RuntimeFailure("cannot read " + path);
  std::uint64_t h = 0xcbf29ce484222325ull, n = 0;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) {
      h ^= static_cast<unsigned char>(buf[i]);
      h *= 0x100000001b3ull;
    }
    n += static_cast<std::uint64_t>(got);
  }
  if (bytes) *bytes = n;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

namespace {
bool is_regular_file(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}
std::string hex64(std::uint64_t h) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}
std::uint64_t fnv(std::uint64_t h, const std::string& s) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  h ^= 0xff;  // separator: ("ab", "c") and ("a", "bc") differ
  return h * 0x100000001b3ull;
}
}  // namespace

std::string RunIdentity::fingerprint() const {
  std::uint64_t h = fnv(0xcbf29ce484222325ull, version);
  for (const auto& w : command) h = fnv(h, w);
  for (const auto& in : inputs) h = fnv(fnv(h, in.path), in.hash);
  return hex64(h);
}

RunIdentity identify_run(const std::vector<std::string>& args, const std::string& version) {
  RunIdentity run;
  run.version = version;
  for (std::size_t k = 0; k < args.size(); ++k) {
    const std::string& a = args[k];
    const auto has_value = [&](const char* name) { return a == name && k + 1 < args.size(); };
    const auto prefixed = [&](const char* name) { return a.rfind(name, 0) == 0; };
    if (has_value("--shard") || has_value("--threads")) {
      ++k;
      continue;
    }
    if (prefixed("--shard=") || prefixed("--threads=") || a == "--quiet" || a == "-q") continue;
    if (has_value("-o") || has_value("--output")) {
      run.output = args[++k];
      run.command.push_back("-o");
      run.command.push_back(kOutputPlaceholder);
      continue;
    }
    if (prefixed("--output=") || (prefixed("-o") && a.size() > 2 && a[2] != '-')) {
      run.output = a.substr(prefixed("--output=") ? 9 : 2);
      run.command.push_back("-o");
      run.command.push_back(kOutputPlaceholder);
      continue;
    }
    run.command.push_back(a);
    if (a[0] != '-' && is_regular_file(a)) {
      RunIdentity::Input in;
      in.path = a;
      in.hash = file_hash(a, &in.bytes);
      run.inputs.push_back(in);
    }
  }
  return run;
}

// --- partial records ------------------------------------------------------------------------

namespace {

Json identity_json(const RunIdentity& run) {
  Json inputs = Json::array();
  for (const auto& in : run.inputs)
    inputs.push_back({{"path", in.path}, {"bytes", in.bytes}, {"hash", in.hash}});
  return {{"command", run.command}, {"output", run.output}, {"inputs", inputs},
          {"microsim_version", run.version}, {"fingerprint", run.fingerprint()}};
}

RunIdentity identity_of(const Json& j) {
  RunIdentity run;
  run.command = j.at("command").get<std::vector<std::string>>();
  run.output = j.at("output").get<std::string>();
  run.version = j.at("microsim_version").get<std::string>();
  for (const auto& in : j.at("inputs"))
    run.inputs.push_back({in.at("path").get<std::string>(), in.at("bytes").get<std::uint64_t>(),
                          in.at("hash").get<std::string>()});
  return run;
}

// Rows of the covered units only; the rest are zero by construction.
Json tallies_json(const Tallies& t) {
  const auto rows = [&](const auto& v, std::size_t width) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    return std::vector<T>(v.begin() + static_cast<std::ptrdiff_t>(t.covered.first * width),
                          v.begin() + static_cast<std::ptrdiff_t>(t.covered.end * width));
  };
  return {{"kind", t.kind},
          {"units", t.units},
          {"covered", {t.covered.first, t.covered.end}},
          {"row_counts", t.row_counts},
          {"row_reals", t.row_reals},
          {"counts", rows(t.counts, t.row_counts)},
          {"reals", rows(t.reals, t.row_reals)},
          {"tail_counts", t.tail_counts},
          {"tail_reals", t.tail_reals}};
}

// Counts are JSON integers in [0, 2^63): a negative count would wrap around, a fraction be cut
// and 1e30 overflow, each giving a merged record that looks right.
constexpr std::uint64_t kMaxCount = std::uint64_t(1) << 63;

std::uint64_t count_of(const Json& x, const std::function<UsageError(const std::string&)>& bad,
                       const std::string& field) {
  // A JSON integer: unsigned as parsed from text, or signed (and not negative) as built in memory.
  const bool integer = x.is_number_unsigned() || (x.is_number_integer() && x.get<std::int64_t>() >= 0);
  if (!integer || x.get<std::uint64_t>() >= kMaxCount)
    throw bad(field + " must be a non-negative integer below 2^63 (got " + x.dump() + ")");
  return x.get<std::uint64_t>();
}

std::vector<std::uint64_t> counts_of(const Json& j, const char* key,
                                     const std::function<UsageError(const std::string&)>& bad) {
  const Json& a = j.at(key);
  if (!a.is_array()) throw bad(std::string(key) + " must be an array of counts");
  std::vector<std::uint64_t> v;
  v.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) v.push_back(count_of(a[i], bad, key + ("[" + std::to_string(i) + "]")));
  return v;
}

std::vector<double> reals_of(const Json& j, const char* key,
                             const std::function<UsageError(const std::string&)>& bad) {
  const Json& a = j.at(key);
  if (!a.is_array()) throw bad(std::string(key) + " must be an array of numbers");
  std::vector<double> v;
  v.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_number() || !std::isfinite(a[i].get<double>()))
      throw bad(key + ("[" + std::to_string(i) + "] must be a finite number (got " + a[i].dump() + ")"));
    v.push_back(a[i].get<double>());
  }
  return v;
}

// One estimator call's tallies of a part; `index` is its place in the part's "tallies".
Tallies tallies_of(const Json& j, const std::string& part, std::size_t index) {
  const std::function<UsageError(const std::string&)> bad = [&](const std::string& why) {
    return UsageError("part " + part + " is not a valid partial record: tallies[" + std::to_string(index) +
                      "]." + why);
  };
  const UnitRange covered{count_of(j.at("covered").at(0), bad, "covered[0]"),
                          count_of(j.at("covered").at(1), bad, "covered[1]")};
  const auto units = count_of(j.at("units"), bad, "units");
  if (covered.first > covered.end || covered.end > units) throw bad("covered: range outside the units");
  const std::uint64_t row_counts = count_of(j.at("row_counts"), bad, "row_counts");
  const std::uint64_t row_reals = count_of(j.at("row_reals"), bad, "row_reals");
  const auto counts = counts_of(j, "counts", bad);
  const auto reals = reals_of(j, "reals", bad);
  // Sizes checked before the tallies are allocated (units * row widths comes from the file).
  if (units > 0 && (row_counts > kMaxCount / units || row_reals > kMaxCount / units))
    throw bad("row_counts: rows too wide for the units");
  if (counts.size() != covered.size() * row_counts || reals.size() != covered.size() * row_reals)
    throw bad("counts: row sizes do not match the covered range");
  require_memory(8.0 * units * (row_counts + row_reals), "part " + literal_text(part) + " (units x row widths)");
  const auto tail_counts = counts_of(j, "tail_counts", bad);
  const auto tail_reals = reals_of(j, "tail_reals", bad);
  Tallies t(j.at("kind").get<std::string>(), units, covered, row_counts, row_reals, tail_counts.size(),
            tail_reals.size());
  std::copy(counts.begin(), counts.end(), t.counts.begin() + static_cast<std::ptrdiff_t>(covered.first * t.row_counts));
  std::copy(reals.begin(), reals.end(), t.reals.begin() + static_cast<std::ptrdiff_t>(covered.first * t.row_reals));
  t.tail_counts = tail_counts;
  t.tail_reals = tail_reals;
  return t;
}

// The run and the shard a part names, its fingerprint checked against the run it states.
struct PartHeader {
  RunIdentity run;
  int index = 0, count = 0;
  std::string fingerprint;
};

PartHeader part_header(const std::string& name, const Json& j) {
  if (!j.is_object() || j.value("format", std::string()) != kPartialFormat)
    throw ParameterError("part " + literal_text(name) + " is not a partial record (no \"format\": \"" +
                         std::string(kPartialFormat) + "\"; written by measure ... {shard} K/N)");
  PartHeader h;
  try {
    h.run = identity_of(j.at("run"));
    h.index = j.at("shard").at("index").get<int>();
    h.count = j.at("shard").at("count").get<int>();
  } catch (const Json::exception& e) {
    throw UsageError("part " + name + " is not a valid partial record: " + e.what());
  }
  h.fingerprint = h.run.fingerprint();
  if (h.fingerprint != j.at("run").value("fingerprint", std::string()))
    throw UsageError("part " + name + " is damaged: its fingerprint does not match its run");
  return h;
}

// Every estimator call's tallies of a part, in the order the run made them.
std::vector<Tallies> part_tallies(const std::string& name, const Json& j) {
  std::vector<Tallies> entries;
  try {
    for (const auto& e : j.at("tallies")) entries.push_back(tallies_of(e, name, entries.size()));
  } catch (const Json::exception& e) {
    throw UsageError("part " + name + " is not a valid partial record: " + e.what());
  }
  return entries;
}

// The parts of one run: the first part fixes the run and the shard count; each later part must
// have the same fingerprint and count, and every shard index must come once.
class ShardSet {
 public:
  void add(const std::string& name, const PartHeader& h) {
    if (seen_.empty()) {
      first_ = h;
      first_name_ = name;
    } else if (h.fingerprint != first_.fingerprint) {
      throw UsageError("part " + name + " belongs to another run than " + first_name_ +
                       " (different command, inputs or version: fingerprint " + h.fingerprint + " vs " +
                       first_.fingerprint + ")");
    } else if (h.count != first_.count) {
      throw UsageError("part " + name + " is shard " + std::to_string(h.index) + "/" + std::to_string(h.count) +
                       ", " + first_name_ + " one of " + std::to_string(first_.count) + " shards");
    }
    const int k = h.index, n = h.count;
    if (!(k >= 1 && k <= n)) throw UsageError("part " + name + " has an invalid shard index");
    if (seen_.count(k))
      throw UsageError("shard " + std::to_string(k) + "/" + std::to_string(n) + " is given twice (" +
                       seen_[k] + " and " + name + ")");
    seen_[k] = name;
  }
  // ParameterError listing the shards no part holds.
  void check_complete() const {
    const int shards = first_.count;
    std::string missing;
    for (int k = 1; k <= shards; ++k)
      if (!seen_.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k) + "/" + std::to_string(shards);
    if (!missing.empty())
      throw ParameterError("shard" + std::string(missing.find(',') != std::string::npos ? "s " : " ") + missing +
                           " missing (run them with {shard} K/N, then merge all " + std::to_string(shards) +
                           " parts)");
  }
  const PartHeader& first() const { return first_; }
  const std::string& first_name() const { return first_name_; }

 private:
  std::map<int, std::string> seen_;  // shard index -> part name
  PartHeader first_;
  std::string first_name_;
};

// The covered ranges of one estimator call's parts tile its units [0, units): no gap, no overlap.
void check_units_tiled(std::vector<UnitRange> ranges, std::size_t e, const Tallies& merged) {
  std::sort(ranges.begin(), ranges.end(),
            [](const UnitRange& a, const UnitRange& b) { return a.first < b.first; });
  std::uint64_t at = 0;
  for (const UnitRange& r : ranges) {
    if (r.size() == 0) continue;
    if (r.first != at)
      throw UsageError("estimator call " + std::to_string(e + 1) + " (" + merged.kind + "): units " +
                       (r.first > at ? "[" + std::to_string(at) + ", " + std::to_string(r.first) + ") missing"
                                     : "from " + std::to_string(r.first) + " covered twice"));
    at = r.end;
  }
  if (at != merged.units)
    throw UsageError("estimator call " + std::to_string(e + 1) + " (" + merged.kind + "): units [" +
                     std::to_string(at) + ", " + std::to_string(merged.units) + ") missing");
}

// Estimator call e merged over the parts (taken in `order`, shard order, so that real totals
// are summed in a fixed order): each part's covered unit rows copied in, the tails summed.
Tallies merge_entry(const std::vector<std::vector<Tallies>>& all, const std::vector<std::size_t>& order,
                    std::size_t e, const std::vector<std::pair<std::string, Json>>& parts,
                    const std::string& first_name) {
  Tallies merged = all[order[0]][e];
  merged.covered = {0, merged.units};
  std::fill(merged.counts.begin(), merged.counts.end(), 0);
  std::fill(merged.reals.begin(), merged.reals.end(), 0.0);
  std::fill(merged.tail_counts.begin(), merged.tail_counts.end(), 0);
  std::fill(merged.tail_reals.begin(), merged.tail_reals.end(), 0.0);
  std::vector<UnitRange> ranges;
  for (std::size_t p : order) {
    const Tallies& t = all[p][e];
    if (!same_layout(t, merged))
      throw UsageError("part " + parts[p].first + ": estimator call " + std::to_string(e + 1) +
                       " is " + describe(t) + ", " + first_name + " has " + describe(merged));
    for (std::uint64_t u = t.covered.first; u < t.covered.end; ++u) {
      std::copy_n(t.counts.begin() + static_cast<std::ptrdiff_t>(u * t.row_counts), t.row_counts,
                  merged.counts.begin() + static_cast<std::ptrdiff_t>(u * t.row_counts));
      std::copy_n(t.reals.begin() + static_cast<std::ptrdiff_t>(u * t.row_reals), t.row_reals,
                  merged.reals.begin() + static_cast<std::ptrdiff_t>(u * t.row_reals));
    }
    for (std::size_t i = 0; i < t.tail_counts.size(); ++i) merged.tail_counts[i] += t.tail_counts[i];
    for (std::size_t i = 0; i < t.tail_reals.size(); ++i) merged.tail_reals[i] += t.tail_reals[i];
    ranges.push_back(t.covered);
  }
  check_units_tiled(std::move(ranges), e, merged);
  return merged;
}

}  // namespace

Json partial_json(const RunIdentity& run, const ShardRecorder& shard, double seconds) {
  Json j;
  j["format"] = kPartialFormat;
  j["schema_version"] = kRecordSchemaVersion;
  j["run"] = identity_json(run);
  j["shard"] = {{"index", shard.index()}, {"count", shard.count()}};
  j["seconds"] = seconds;
  Json entries = Json::array();
  for (const Tallies& t : shard.entries()) entries.push_back(tallies_json(t));
  j["tallies"] = entries;
  return j;
}

MergedRun merge_partials(const std::vector<std::pair<std::string, Json>>& parts) {
  if (parts.empty()) throw UsageError("merge needs at least one partial record");
  ShardSet shards;
  std::vector<std::vector<Tallies>> all;
  for (const auto& [name, j] : parts) {
    shards.add(name, part_header(name, j));
    all.push_back(part_tallies(name, j));
  }
  shards.check_complete();
  MergedRun m;
  m.run = shards.first().run;
  m.shards = shards.first().count;

  // Entry by entry: the same layout in every part, covered ranges tiling the units.
  const std::size_t ne = all[0].size();
  for (std::size_t p = 1; p < all.size(); ++p)
    if (all[p].size() != ne)
      throw UsageError("part " + parts[p].first + " holds " + std::to_string(all[p].size()) +
                       " estimator calls, " + shards.first_name() + " " + std::to_string(ne));
  // Parts in shard order, so that real totals are summed in a fixed order.
  std::vector<std::size_t> order(all.size());
  for (std::size_t p = 0; p < all.size(); ++p)
    order[static_cast<std::size_t>(parts[p].second.at("shard").at("index").get<int>() - 1)] = p;
  for (std::size_t e = 0; e < ne; ++e) m.entries.push_back(merge_entry(all, order, e, parts, shards.first_name()));
  return m;
}

}  // namespace microsim
