// cgal_surface_mesher: CGAL Surface_mesher (Boissonnat-Oudot restricted Delaunay refinement)
// on the catalog implicit surfaces.
//
//   cgal_surface_mesher --surface NAME [--angle 30] --radius R --distance D [--manifold]
//                       [--error-bound 1e-3] [--seed 0] [--initial-points 20] [--output F.off]
//
// make_surface_mesh(c2t3, Implicit_surface_3, Surface_mesh_default_criteria_3(angle, radius,
// distance), Non_manifold_tag | Manifold_tag). Only make_surface_mesh is timed. Prints:
//   {"tool":"cgal","bench":"surface","surface":..,"angle":..,"radius":..,"distance":..,
//    "manifold":..,"error_bound":..,"seed":..,"seconds":..,"vertices":..,"facets":..,
//    "edges":..,"euler":..,"boundary_edges":..,"nonmanifold_edges":..,
//    "triangulation_vertices":..,"f_evals":..,"peak_rss_bytes":..,"cgal_version":..}
//
// Bounding sphere passed to CGAL: center = the catalog `inside` point (f < 0 there, as CGAL's
// initial-point search needs), radius = catalog radius + |inside - catalog center|, so that it
// holds the catalog sphere. --error-bound is relative to the CATALOG radius (CGAL's own
// default, 1e-3, relative to the sphere you give it): the bisection along segments stops at
// an absolute length of error_bound * catalog radius.
#include "common.hpp"
#include "mesh_stats.hpp"
#include "surfaces.hpp"

#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Random.h>
#include <CGAL/Surface_mesh_default_criteria_3.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

typedef CGAL::Surface_mesh_default_triangulation_3 Tr;
typedef CGAL::Complex_2_in_triangulation_3<Tr> C2t3;
typedef Tr::Geom_traits GT;
typedef GT::Sphere_3 Sphere_3;
typedef GT::Point_3 Point_3;
typedef GT::FT FT;
typedef FT (*Function)(Point_3);
typedef CGAL::Implicit_surface_3<GT, Function> Surface_3;

static long long g_evals = 0;

int main(int argc, char** argv) {
  bench::Args args(argc, argv, {"--manifold"});
  if (args.has("--help")) {
    std::fprintf(stderr,
                 "usage: cgal_surface_mesher --surface NAME [--angle 30] --radius R --distance D "
                 "[--manifold] [--error-bound 1e-3] [--seed 0] [--initial-points 20] "
                 "[--output F.off]\nsurfaces: %s\n",
                 bench::catalog_names().c_str());
    return 0;
  }
  std::string name = args.str("--surface", "");
  const bench::CatalogSurface* surf = bench::find_surface(name);
  if (!surf)
    bench::fail("--surface '" + name + "' is not in the catalog; use one of " +
                bench::catalog_names());
  double angle = args.num("--angle", 30.0);
  if (!args.has("--radius") || !args.has("--distance"))
    bench::fail("--radius R and --distance D are required");
  double radius = args.num("--radius", 0);
  double distance = args.num("--distance", 0);
  double error_bound = args.num("--error-bound", 1e-3);
  std::uint64_t seed = args.u64("--seed", 0);
  std::uint64_t n_init = args.u64("--initial-points", 20);
  bool manifold = args.has("--manifold");
  std::string output = args.str("--output", "");
  args.reject_unknown();
  if (!(angle >= 0 && angle <= 30))
    bench::fail("--angle " + bench::json_num(angle) +
                " is out of range; use 0..30 degrees (refinement may not end above 30)");
  if (!(radius > 0)) bench::fail("--radius must be > 0");
  if (!(distance > 0)) bench::fail("--distance must be > 0");
  if (!(error_bound > 0 && error_bound < 1)) bench::fail("--error-bound must be in (0, 1)");
  if (n_init < 1 || n_init > 100000) bench::fail("--initial-points must be in 1..100000");

  const double* c0 = surf->center;
  const double* in = surf->inside;
  double f_in = surf->f(in[0], in[1], in[2]);
  if (!(f_in < 0)) bench::fail("internal: catalog inside point of " + name + " has f >= 0");
  double shift = std::sqrt(bench::sq(in[0] - c0[0]) + bench::sq(in[1] - c0[1]) +
                           bench::sq(in[2] - c0[2]));
  double big_r = surf->radius + shift;
  double cgal_error_bound = error_bound * surf->radius / big_r;

  auto fn = surf->f;
  Surface_3 surface(
      [fn](Point_3 p) -> FT {
        ++g_evals;
        return fn(p.x(), p.y(), p.z());
      },
      Sphere_3(Point_3(in[0], in[1], in[2]), big_r * big_r),  // squared radius!
      cgal_error_bound);
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(angle, radius, distance);

  CGAL::get_default_random() = CGAL::Random(static_cast<unsigned int>(seed));
  Tr tr;
  C2t3 c2t3(tr);
  bench::Timer timer;
  if (manifold)
    CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag(),
                            static_cast<int>(n_init));
  else
    CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Non_manifold_tag(),
                            static_cast<int>(n_init));
  double secs = timer.seconds();
  long long evals = g_evals;

  bench::MeshStats st = bench::mesh_stats(c2t3);
  if (!output.empty()) bench::write_off(c2t3, output);

  bench::Json j;
  j.s("tool", "cgal").s("bench", "surface").s("surface", name);
  j.d("angle", angle).d("radius", radius).d("distance", distance).b("manifold", manifold);
  j.d("error_bound", error_bound).i("seed", static_cast<long long>(seed));
  j.d("seconds", secs);
  bench::add_stats(j, st);
  j.i("f_evals", evals).i("peak_rss_bytes", bench::peak_rss_bytes());
  j.s("cgal_version", bench::cgal_version());
  j.print();
  return 0;
}
