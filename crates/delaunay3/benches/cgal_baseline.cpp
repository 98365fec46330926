// CGAL baseline for the delaunay3 benchmarks: same points as examples/bench_points.rs
// (SplitMix64), CGAL 5.x Delaunay_triangulation_3 with Epick, range insertion (which
// spatially sorts). Prints one JSON object. Build and run through benches/cgal_baseline.sh.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_3<K> DT;
typedef K::Point_3 P;

struct SplitMix {
  uint64_t s;
  double unit() {
    s += 0x9E3779B97F4A7C15ULL;
    uint64_t z = s;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z = z ^ (z >> 31);
    return (double)(z >> 11) / (double)(1ULL << 53);
  }
};

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s N SEED cube|sphere\n", argv[0]);
    return 2;
  }
  size_t n = std::strtoull(argv[1], nullptr, 10);
  SplitMix r{std::strtoull(argv[2], nullptr, 10)};
  std::string dist = argv[3];
  std::vector<P> pts;
  pts.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (dist == "sphere") {
      for (;;) {
        double x = r.unit() * 2.0 - 1.0, y = r.unit() * 2.0 - 1.0, z = r.unit() * 2.0 - 1.0;
        double l = x * x + y * y + z * z;
        if (l > 1e-6 && l <= 1.0) {
          double s = std::sqrt(l);
          pts.emplace_back(x / s, y / s, z / s);
          break;
        }
      }
    } else {
      double x = r.unit(), y = r.unit(), z = r.unit();
      pts.emplace_back(x, y, z);
    }
  }
  auto t0 = std::chrono::steady_clock::now();
  DT dt(pts.begin(), pts.end());
  auto t1 = std::chrono::steady_clock::now();
  double s = std::chrono::duration<double>(t1 - t0).count();
  std::printf("{\"impl\":\"cgal\",\"points\":%zu,\"vertices\":%zu,\"finite_cells\":%zu,\"seconds\":%.4f,\"valid\":%s}\n",
              n, (size_t)dt.number_of_vertices(), (size_t)dt.number_of_finite_cells(), s,
              n <= 200000 ? (dt.is_valid() ? "true" : "false") : "null");
  return 0;
}
