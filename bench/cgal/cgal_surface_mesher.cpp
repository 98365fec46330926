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
#include "surface_run.hpp"
#include "surfaces.hpp"

#include <CGAL/Implicit_surface_3.h>

using bench::FT;
using bench::GT;
using bench::Point_3;
using bench::Sphere_3;
typedef FT (*Function)(Point_3);
typedef CGAL::Implicit_surface_3<GT, Function> Surface_3;

int main(int argc, char** argv) {
  bench::Args args = bench::mesher_args(
      argc, argv,
      "usage: cgal_surface_mesher --surface NAME [--angle 30] --radius R --distance D "
      "[--manifold] [--error-bound 1e-3] [--seed 0] [--initial-points 20] "
      "[--output F.off]\nsurfaces: " +
          bench::catalog_names());
  std::string name = args.str("--surface", "");
  const bench::CatalogSurface* surf = bench::find_surface(name);
  if (!surf)
    bench::fail("--surface '" + name + "' is not in the catalog; use one of " +
                bench::catalog_names());
  bench::MeshArgs m = bench::mesh_args(args);
  std::uint64_t n_init = args.u64("--initial-points", 20);
  args.reject_unknown();
  if (n_init < 1 || n_init > 100000) bench::fail("--initial-points must be in 1..100000");

  const double* c0 = surf->center;
  const double* in = surf->inside;
  double f_in = surf->f(in[0], in[1], in[2]);
  if (!(f_in < 0)) bench::fail("internal: catalog inside point of " + name + " has f >= 0");
  double shift = std::sqrt(bench::sq(in[0] - c0[0]) + bench::sq(in[1] - c0[1]) +
                           bench::sq(in[2] - c0[2]));
  double big_r = surf->radius + shift;
  double cgal_error_bound = m.error_bound * surf->radius / big_r;

  auto fn = surf->f;
  Surface_3 surface(
      [fn](Point_3 p) -> FT {
        ++bench::g_evals;
        return fn(p.x(), p.y(), p.z());
      },
      Sphere_3(Point_3(in[0], in[1], in[2]), big_r * big_r),  // squared radius!
      cgal_error_bound);
  bench::MeshRun run = bench::run_mesher(surface, m, static_cast<int>(n_init));
  long long evals = bench::g_evals;

  bench::Json j;
  j.s("tool", "cgal").s("bench", "surface").s("surface", name);
  bench::add_mesh_args(j, m);
  j.d("seconds", run.seconds);
  bench::finish_json(j, run.stats, evals);
  return 0;
}
