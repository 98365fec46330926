// cgal_image_mesher: CGAL Surface_mesher on a grey-level 3D image (Gray_level_image_3 +
// Implicit_surface_3), as in CGAL's mesh_a_3d_gray_image example.
//
//   cgal_image_mesher --tanglecube-grid N [--write-inr F.inr] [--iso 0] [--angle 30]
//                     --radius R --distance D [--manifold] [--error-bound 1e-3] [--seed 0]
//                     [--output F.off]
//   cgal_image_mesher --input vol.inr --center X,Y,Z --sphere-radius B [--origin X,Y,Z]
//                     [--iso V] [--inside below|above] [--angle 30] --radius R --distance D ...
//
// --tanglecube-grid N samples the catalog tanglecube f = x^4-5x^2+y^4-5y^2+z^4-5z^2+11.8 as
// float32 at the N^3 nodes x_i = -4 + i*h, h = 8/(N-1), i = 0..N-1 (same for y, z; x fastest in
// memory), so the grid spans [-4,4]^3 exactly; writes it as an INR file (hand-written 256-byte
// INRIMAGE-4 header, TYPE=float, CPU=decm, VX=VY=VZ=h printed with 17 digits; default path
// $TMPDIR/cgal_tanglecube_N.inr, or --write-inr) and meshes it back through CGAL's reader.
// Inside = value < iso (f < 0). Everything (criteria, sphere, output) is in WORLD units: CGAL
// samples the image at (p - origin) where origin = (-4,-4,-4) here (CGAL's trilinear
// interpolation ignores the INR translation fields, so we translate ourselves). The bounding
// sphere is centered at the inside point (sqrt 2.5)(1,1,1) with radius 4 + |that point| (it
// holds the catalog sphere of radius 4); --error-bound is relative to 4 (the catalog radius).
//
// Only make_surface_mesh is timed ("seconds"); reading the image is "load_seconds". Prints:
//   {"tool":"cgal","bench":"image","input":..,"grid":"NXxNYxNZ","voxel_size":..,"iso":..,"angle":..,
//    "radius":..,"distance":..,"manifold":..,"error_bound":..,"seed":..,"seconds":..,
//    "load_seconds":..,"vertices":..,"facets":..,"edges":..,"euler":..,"boundary_edges":..,
//    "nonmanifold_edges":..,"triangulation_vertices":..,"f_evals":..,"peak_rss_bytes":..,
//    "cgal_version":..}
#include "surface_run.hpp"
#include "surfaces.hpp"

#include <CGAL/Gray_level_image_3.h>
#include <CGAL/Implicit_surface_3.h>

#include <cstring>
#include <fstream>

using bench::FT;
using bench::GT;
using bench::Point_3;
using bench::Sphere_3;
typedef CGAL::Gray_level_image_3<FT, Point_3> Gray_level_image;
typedef CGAL::Implicit_surface_3<GT, Gray_level_image> Surface_3;

static void write_tanglecube_inr(const std::string& path, std::size_t n) {
  const double h = 8.0 / static_cast<double>(n - 1);
  std::vector<float> data(n * n * n);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < n; ++i) {
        double x = -4.0 + static_cast<double>(i) * h;
        double y = -4.0 + static_cast<double>(j) * h;
        double z = -4.0 + static_cast<double>(k) * h;
        data[(k * n + j) * n + i] = static_cast<float>(bench::f_tanglecube(x, y, z));
      }
  char hb[64];
  std::snprintf(hb, sizeof hb, "%.17g", h);
  std::string hdr = "#INRIMAGE-4#{\n";
  hdr += "XDIM=" + std::to_string(n) + "\nYDIM=" + std::to_string(n) + "\nZDIM=" +
         std::to_string(n) + "\nVDIM=1\nTYPE=float\nPIXSIZE=32 bits\nCPU=decm\n";
  hdr += std::string("VX=") + hb + "\nVY=" + hb + "\nVZ=" + hb + "\n";
  if (hdr.size() > 252) bench::fail("internal: INR header too long");
  hdr += std::string(252 - hdr.size(), '\n');
  hdr += "##}\n";
  std::uint32_t one = 1;
  unsigned char little;
  std::memcpy(&little, &one, 1);
  if (little != 1) bench::fail("this writer assumes a little-endian machine (CPU=decm)");
  std::ofstream out(path, std::ios::binary);
  if (!out) bench::fail("cannot create INR file '" + path + "'");
  out.write(hdr.data(), static_cast<std::streamsize>(hdr.size()));
  out.write(reinterpret_cast<const char*>(data.data()),
            static_cast<std::streamsize>(data.size() * sizeof(float)));
  if (!out) bench::fail("write error on INR file '" + path + "'");
}

static void parse3(const std::string& opt, const std::string& v, double out[3]) {
  char c1 = 0, c2 = 0;
  std::istringstream is(v);
  std::string rest;
  if (!(is >> out[0] >> c1 >> out[1] >> c2 >> out[2]) || c1 != ',' || c2 != ',' ||
      (is >> rest) || !std::isfinite(out[0]) || !std::isfinite(out[1]) || !std::isfinite(out[2]))
    bench::fail("option " + opt + ": '" + v + "' is not three finite numbers 'X,Y,Z'");
}

int main(int argc, char** argv) {
  bench::Args args = bench::mesher_args(
      argc, argv,
      "usage: cgal_image_mesher --tanglecube-grid N [--write-inr F.inr] | --input vol.inr "
      "--center X,Y,Z --sphere-radius B [--origin X,Y,Z] [--inside below|above]\n  [--iso 0] "
      "[--angle 30] --radius R --distance D [--manifold] [--error-bound 1e-3] [--seed 0] "
      "[--output F.off]");
  std::string path;
  double origin[3] = {0, 0, 0}, center[3] = {0, 0, 0};
  double sphere_r = 0, rel_r = 0;  // CGAL sphere radius; radius the error bound refers to
  bool inside_below = true;
  if (args.has("--tanglecube-grid")) {
    if (args.has("--input")) bench::fail("give either --tanglecube-grid N or --input FILE");
    std::uint64_t n = args.u64("--tanglecube-grid", 0);
    if (n < 8 || n > 1024) bench::fail("--tanglecube-grid N needs 8 <= N <= 1024");
    const char* tmp = std::getenv("TMPDIR");
    path = args.str("--write-inr", std::string(tmp && *tmp ? tmp : "/tmp") +
                                       "/cgal_tanglecube_" + std::to_string(n) + ".inr");
    write_tanglecube_inr(path, static_cast<std::size_t>(n));
    const bench::CatalogSurface* tc = bench::find_surface("tanglecube");
    for (int k = 0; k < 3; ++k) {
      origin[k] = -4.0;
      center[k] = tc->inside[k];
    }
    rel_r = tc->radius;
    sphere_r = rel_r + std::sqrt(center[0] * center[0] + center[1] * center[1] +
                                 center[2] * center[2]);
  } else if (args.has("--input")) {
    path = args.str("--input", "");
    if (!args.has("--center") || !args.has("--sphere-radius"))
      bench::fail("--input needs --center X,Y,Z (a point inside the solid) and --sphere-radius B "
                  "(a sphere around it holding the whole surface), in world units");
    parse3("--center", args.str("--center", ""), center);
    sphere_r = rel_r = args.num("--sphere-radius", 0);
    if (!(sphere_r > 0)) bench::fail("--sphere-radius must be > 0");
    if (args.has("--origin")) parse3("--origin", args.str("--origin", ""), origin);
    std::string inside = args.str("--inside", "below");
    if (inside != "below" && inside != "above")
      bench::fail("--inside '" + inside + "': use below (value < iso is inside) or above");
    inside_below = inside == "below";
  } else {
    bench::fail("give --tanglecube-grid N or --input vol.inr (see --help)");
  }
  double iso = args.num("--iso", 0.0);
  bench::MeshArgs m = bench::mesh_args(args);
  args.reject_unknown();

  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) bench::fail("cannot open image file '" + path + "'");
  }
  const float fiso = static_cast<float>(iso);
  // value returned for points outside the grid: "outside" of the solid.
  const float outside_value = inside_below ? fiso + 1e6f : fiso - 1e6f;
  bench::Timer load_timer;
  Gray_level_image image(path, fiso, /*positive_inside=*/!inside_below, outside_value);
  double load_secs = load_timer.seconds();
  if (image.image() == nullptr || image.xdim() < 2 || image.ydim() < 2 || image.zdim() < 2)
    bench::fail("CGAL could not read a 3D image from '" + path + "' (INR, ANALYZE, ...)");
  if (!(image(Point_3(center[0] - origin[0], center[1] - origin[1], center[2] - origin[2])) < 0))
    bench::fail("the bounding sphere center is not inside the solid (image value vs iso): "
                "give --center at a point where the solid is");

  const double ox = origin[0], oy = origin[1], oz = origin[2];
  const Gray_level_image& img = image;
  Surface_3 surface(
      [&img, ox, oy, oz](Point_3 p) -> FT {
        ++bench::g_evals;
        return img(Point_3(p.x() - ox, p.y() - oy, p.z() - oz));
      },
      Sphere_3(Point_3(center[0], center[1], center[2]), sphere_r * sphere_r),  // squared!
      m.error_bound * rel_r / sphere_r);
  // CGAL's default number of initial points (20), as make_surface_mesh without it.
  bench::MeshRun run = bench::run_mesher(surface, m, 20);
  long long evals = bench::g_evals;

  bench::Json j;
  j.s("tool", "cgal").s("bench", "image").s("input", path);
  j.s("grid", std::to_string(image.xdim()) + "x" + std::to_string(image.ydim()) + "x" +
                  std::to_string(image.zdim()));
  j.d("voxel_size", image.vx()).d("iso", iso);
  bench::add_mesh_args(j, m);
  j.d("seconds", run.seconds).d("load_seconds", load_secs);
  bench::finish_json(j, run.stats, evals);
  return 0;
}
