// What cgal_surface_mesher and cgal_image_mesher share: the Surface_mesher refinement options,
// the timed make_surface_mesh call and the JSON fields around it.
#pragma once

#include "common.hpp"
#include "mesh_stats.hpp"

#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh_default_criteria_3.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace bench {

typedef CGAL::Surface_mesh_default_triangulation_3 Tr;
typedef CGAL::Complex_2_in_triangulation_3<Tr> C2t3;
typedef Tr::Geom_traits GT;
typedef GT::Sphere_3 Sphere_3;
typedef GT::Point_3 Point_3;
typedef GT::FT FT;

// Evaluations of the surface function (the programs' Surface_3 functions count them).
inline long long g_evals = 0;

// The command line of a mesher program (the flag --manifold takes no value); with --help,
// prints `usage` on stderr and exits 0.
inline Args mesher_args(int argc, char** argv, const std::string& usage) {
  Args args(argc, argv, {"--manifold"});
  if (args.has("--help")) {
    std::fprintf(stderr, "%s\n", usage.c_str());
    std::exit(0);
  }
  return args;
}

// --angle (default 30) --radius --distance --error-bound (default 1e-3) --seed (default 0)
// --manifold --output.
struct MeshArgs {
  double angle, radius, distance, error_bound;
  std::uint64_t seed;
  bool manifold;
  std::string output;
};

// Parses and checks the refinement options (call before Args::reject_unknown).
inline MeshArgs mesh_args(Args& args) {
  MeshArgs m;
  m.angle = args.num("--angle", 30.0);
  if (!args.has("--radius") || !args.has("--distance"))
    fail("--radius R and --distance D are required");
  m.radius = args.num("--radius", 0);
  m.distance = args.num("--distance", 0);
  m.error_bound = args.num("--error-bound", 1e-3);
  m.seed = args.u64("--seed", 0);
  m.manifold = args.has("--manifold");
  m.output = args.str("--output", "");
  if (!(m.angle >= 0 && m.angle <= 30))
    fail("--angle " + json_num(m.angle) +
         " is out of range; use 0..30 degrees (refinement may not end above 30)");
  if (!(m.radius > 0)) fail("--radius must be > 0");
  if (!(m.distance > 0)) fail("--distance must be > 0");
  if (!(m.error_bound > 0 && m.error_bound < 1)) fail("--error-bound must be in (0, 1)");
  return m;
}

struct MeshRun {
  double seconds;  // make_surface_mesh only
  MeshStats stats;
};

// make_surface_mesh with Surface_mesh_default_criteria_3(angle, radius, distance), Manifold_tag
// or Non_manifold_tag, CGAL's default random generator seeded with --seed; writes --output.
template <class Surface>
MeshRun run_mesher(const Surface& surface, const MeshArgs& m, int initial_points) {
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(m.angle, m.radius, m.distance);
  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned int>(m.seed));
  Tr tr;
  C2t3 c2t3(tr);
  Timer timer;
  if (m.manifold)
    CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag(), initial_points);
  else
    CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Non_manifold_tag(), initial_points);
  MeshRun run{timer.seconds(), mesh_stats(c2t3)};
  if (!m.output.empty()) write_off(c2t3, m.output);
  return run;
}

// The refinement options' JSON fields.
inline void add_mesh_args(Json& j, const MeshArgs& m) {
  j.d("angle", m.angle).d("radius", m.radius).d("distance", m.distance).b("manifold", m.manifold);
  j.d("error_bound", m.error_bound).i("seed", static_cast<long long>(m.seed));
}

// The closing JSON fields (mesh statistics, evaluations, memory, CGAL version); prints the line.
inline void finish_json(Json& j, const MeshStats& st, long long evals) {
  add_stats(j, st);
  j.i("f_evals", evals).i("peak_rss_bytes", peak_rss_bytes());
  j.s("cgal_version", cgal_version());
  j.print();
}

}  // namespace bench
