// Shared helpers for the CGAL baseline programs of the rdt-mesher benchmark suite.
//
// Every program prints exactly ONE JSON line on stdout (the figures) and diagnostics on
// stderr. On bad input it prints "error: ..." on stderr and exits with status 2.
#pragma once

#include <CGAL/version.h>

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace bench {

[[noreturn]] inline void fail(const std::string& msg) {
  std::fprintf(stderr, "error: %s\n", msg.c_str());
  std::exit(2);
}

// SplitMix64 (Steele, Lea, Flood 2014), the generator shared with the Rust side.
//   state starts at `seed`; next(): state += 0x9E3779B97F4A7C15; z = state;
//   z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9; z = (z ^ (z >> 27)) * 0x94D049BB133111EB;
//   return z ^ (z >> 31)            (all arithmetic wrapping mod 2^64)
//   uniform(): (next() >> 11) * 2^-53, a double in [0, 1).
struct SplitMix64 {
  std::uint64_t state;
  explicit SplitMix64(std::uint64_t seed) : state(seed) {}
  std::uint64_t next() {
    state += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

// Points of the benchmark distributions, bit-identical to the Rust generator (IEEE f64,
// no FMA contraction: build with -ffp-contract=off).
//  cube:   x = u(), y = u(), z = u()  (in this order), in [0,1)^3.
//  sphere: repeat { x = 2u()-1; y = 2u()-1; z = 2u()-1; s = (x*x + y*y) + z*z }
//          until 0 < s <= 1; point = (x/sqrt(s), y/sqrt(s), z/sqrt(s)) (unit sphere).
struct P3 {
  double x, y, z;
};

inline std::vector<P3> generate_points(const std::string& distribution, std::size_t n,
                                       std::uint64_t seed) {
  SplitMix64 rng(seed);
  std::vector<P3> pts;
  pts.reserve(n);
  if (distribution == "cube") {
    for (std::size_t i = 0; i < n; ++i) {
      double x = rng.uniform();
      double y = rng.uniform();
      double z = rng.uniform();
      pts.push_back({x, y, z});
    }
  } else if (distribution == "sphere") {
    while (pts.size() < n) {
      double x = 2.0 * rng.uniform() - 1.0;
      double y = 2.0 * rng.uniform() - 1.0;
      double z = 2.0 * rng.uniform() - 1.0;
      double s = (x * x + y * y) + z * z;
      if (!(s > 0.0 && s <= 1.0)) continue;
      double r = std::sqrt(s);
      pts.push_back({x / r, y / r, z / r});
    }
  } else {
    fail("unknown --distribution '" + distribution + "'; use cube or sphere");
  }
  return pts;
}

inline long long peak_rss_bytes() {
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) != 0) return -1;
  return static_cast<long long>(ru.ru_maxrss) * 1024LL;  // Linux: kilobytes
}

class Timer {
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();

 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
};

// Minimal command line: --key value (or --key=value) pairs and --flag switches.
class Args {
  std::map<std::string, std::string> kv_;
  std::map<std::string, bool> used_;

 public:
  Args(int argc, char** argv, const std::vector<std::string>& flags) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0) fail("unexpected argument '" + a + "' (options start with --)");
      std::size_t eq = a.find('=');
      if (eq != std::string::npos) {  // --key=value
        kv_[a.substr(0, eq)] = a.substr(eq + 1);
        continue;
      }
      bool is_flag = false;
      for (const auto& f : flags) is_flag |= (f == a);
      if (is_flag || a == "--help") {
        kv_[a] = "1";
      } else {
        if (i + 1 >= argc) fail("option " + a + " needs a value");
        kv_[a] = argv[++i];
      }
    }
  }
  bool has(const std::string& k) {
    used_[k] = true;
    return kv_.count(k) != 0;
  }
  std::string str(const std::string& k, const std::string& def) {
    return has(k) ? kv_[k] : def;
  }
  double num(const std::string& k, double def) {
    if (!has(k)) return def;
    const std::string& v = kv_[k];
    char* end = nullptr;
    double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(d))
      fail("option " + k + ": '" + v + "' is not a finite number");
    return d;
  }
  std::uint64_t u64(const std::string& k, std::uint64_t def) {
    if (!has(k)) return def;
    const std::string& v = kv_[k];
    // accept 1e6 style too
    char* end = nullptr;
    double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !(d >= 0) || d > 1.8e19 || d != std::floor(d))
      fail("option " + k + ": '" + v + "' is not a non-negative integer");
    if (v.find_first_not_of("0123456789") == std::string::npos)
      return std::strtoull(v.c_str(), nullptr, 10);
    return static_cast<std::uint64_t>(d);
  }
  void reject_unknown() {
    for (const auto& p : kv_)
      if (!used_.count(p.first)) fail("unknown option " + p.first + " (see --help)");
  }
};

inline std::string json_str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else {
      o += c;
    }
  }
  return o + "\"";
}

inline std::string json_num(double d) {
  char b[64];
  std::snprintf(b, sizeof b, "%.9g", d);
  return b;
}

inline std::string cgal_version() { return CGAL_VERSION_STR; }

// Builds one JSON object line, keys in insertion order.
class Json {
  std::ostringstream os_;
  bool first_ = true;
  void key(const std::string& k) {
    os_ << (first_ ? "{" : ",") << json_str(k) << ":";
    first_ = false;
  }

 public:
  Json& s(const std::string& k, const std::string& v) {
    key(k);
    os_ << json_str(v);
    return *this;
  }
  Json& d(const std::string& k, double v) {
    key(k);
    os_ << json_num(v);
    return *this;
  }
  Json& i(const std::string& k, long long v) {
    key(k);
    os_ << v;
    return *this;
  }
  Json& b(const std::string& k, bool v) {
    key(k);
    os_ << (v ? "true" : "false");
    return *this;
  }
  void print() {
    std::printf("%s}\n", os_.str().c_str());
    std::fflush(stdout);
  }
};

}  // namespace bench
