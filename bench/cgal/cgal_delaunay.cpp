// cgal_delaunay: CGAL Delaunay_triangulation_3<Epick> range insertion benchmark.
//
//   cgal_delaunay --random N [--seed S] [--distribution cube|sphere] [--check]
//   cgal_delaunay --input points.xyz [--check]
//   --dump-points F.xyz additionally writes the input points ("%.17g %.17g %.17g" per line),
//   so that the Rust generator can be checked bit for bit against this one.
//
// Times only `T.insert(points.begin(), points.end())` (CGAL spatially sorts the range
// before inserting). Prints one JSON line:
//   {"tool":"cgal","bench":"delaunay","n":..,"distribution":..,"seed":..,"seconds":..,
//    "vertices":..,"finite_cells":..,"peak_rss_bytes":..,"valid":..,"cgal_version":..}
// "valid" is present only with --check (T.is_valid(), not timed).
#include "common.hpp"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <fstream>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_3<K> DT;
typedef K::Point_3 Point;

static std::vector<bench::P3> read_xyz(const std::string& path) {
  std::ifstream in(path);
  if (!in) bench::fail("cannot open --input file '" + path + "'");
  std::vector<bench::P3> pts;
  std::string line;
  std::size_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::size_t p = line.find_first_not_of(" \t\r");
    if (p == std::string::npos || line[p] == '#') continue;
    std::istringstream ls(line);
    double x, y, z;
    if (!(ls >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      bench::fail(path + ":" + std::to_string(lineno) +
                  ": expected three finite numbers 'x y z' (extra columns are ignored), got '" +
                  line + "'");
    pts.push_back({x, y, z});
  }
  if (pts.empty()) bench::fail("--input file '" + path + "' holds no points");
  return pts;
}

int main(int argc, char** argv) {
  bench::Args args(argc, argv, {"--check"});
  if (args.has("--help")) {
    std::fprintf(stderr,
                 "usage: cgal_delaunay --random N [--seed S] [--distribution cube|sphere] "
                 "[--check] [--dump-points F]\n       cgal_delaunay --input points.xyz [--check]\n");
    return 0;
  }
  std::vector<bench::P3> raw;
  std::string distribution;
  std::uint64_t seed = 0;
  if (args.has("--input")) {
    if (args.has("--random")) bench::fail("give either --random N or --input FILE, not both");
    std::string path = args.str("--input", "");
    raw = read_xyz(path);
    distribution = "file:" + path;
  } else if (args.has("--random")) {
    std::uint64_t n = args.u64("--random", 0);
    if (n == 0) bench::fail("--random N needs N >= 1");
    seed = args.u64("--seed", 0);
    distribution = args.str("--distribution", "cube");
    raw = bench::generate_points(distribution, n, seed);
  } else {
    bench::fail("give --random N or --input FILE (see --help)");
  }
  bool check = args.has("--check");
  std::string dump = args.str("--dump-points", "");
  args.reject_unknown();
  if (!dump.empty()) {
    FILE* fp = std::fopen(dump.c_str(), "w");
    if (!fp) bench::fail("cannot create --dump-points file '" + dump + "'");
    for (const auto& p : raw) std::fprintf(fp, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
    if (std::fclose(fp) != 0) bench::fail("write error on --dump-points file '" + dump + "'");
  }

  std::vector<Point> pts;
  pts.reserve(raw.size());
  for (const auto& p : raw) pts.emplace_back(p.x, p.y, p.z);
  std::vector<bench::P3>().swap(raw);

  DT T;
  bench::Timer timer;
  T.insert(pts.begin(), pts.end());
  double secs = timer.seconds();

  bench::Json j;
  j.s("tool", "cgal").s("bench", "delaunay").i("n", static_cast<long long>(pts.size()));
  j.s("distribution", distribution).i("seed", static_cast<long long>(seed));
  j.d("seconds", secs);
  j.i("vertices", static_cast<long long>(T.number_of_vertices()));
  j.i("finite_cells", static_cast<long long>(T.number_of_finite_cells()));
  j.i("peak_rss_bytes", bench::peak_rss_bytes());
  if (check) j.b("valid", T.is_valid());
  j.s("cgal_version", bench::cgal_version());
  j.print();
  return 0;
}
