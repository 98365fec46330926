// The implicit surfaces of /work/shared/catalog/implicit_surfaces.json as native C++.
// The solid is where f < 0. `center`/`radius` is the catalog bounding sphere (f > 0 on it and
// outside). `inside` is a point with f < 0 that we use as the center of the sphere given to
// CGAL (CGAL's Implicit_surface_oracle_3 shoots its initial rays from the sphere center and
// needs a sign change along them; the catalog center is outside the solid for torus,
// tanglecube and chair).
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace bench {

struct CatalogSurface {
  const char* name;
  double (*f)(double, double, double);
  double center[3];
  double radius;
  double inside[3];
};

inline double sq(double a) { return a * a; }

inline double f_sphere(double x, double y, double z) { return x * x + y * y + z * z - 1; }
inline double f_ellipsoid(double x, double y, double z) {
  return x * x + sq(y / 0.6) + sq(z / 0.4) - 1;
}
inline double f_torus(double x, double y, double z) {
  return sq(x * x + y * y + z * z + 1 - 0.09) - 4 * (x * x + y * y);
}
inline double f_double_torus(double x, double y, double z) {
  return sq(x * sq(x - 1) * (x - 2) + y * y) + z * z - 0.03;
}
inline double f_tanglecube(double x, double y, double z) {
  double x2 = x * x, y2 = y * y, z2 = z * z;
  return x2 * x2 - 5 * x2 + y2 * y2 - 5 * y2 + z2 * z2 - 5 * z2 + 11.8;
}
inline double f_chair(double x, double y, double z) {
  return sq(x * x + y * y + z * z - 0.95 * 25) -
         0.8 * (sq(z - 5) - 2 * x * x) * (sq(z + 5) - 2 * y * y);
}
inline double f_blobs(double x, double y, double z) {
  return 0.5 - std::exp(-(sq(x - 0.5) + y * y + z * z) / 0.2) -
         std::exp(-(sq(x + 0.5) + y * y + z * z) / 0.2) -
         std::exp(-(x * x + sq(y - 0.6) + z * z) / 0.1);
}
inline double f_heart(double x, double y, double z) {
  double z3 = z * z * z;
  return std::pow(x * x + 2.25 * y * y + z * z - 1, 3) - x * x * z3 - 0.1125 * y * y * z3;
}

inline const std::vector<CatalogSurface>& catalog() {
  // sqrt(2.5) = 1.5811388300841898: tanglecube f(s,s,s) = -6.95.
  static const std::vector<CatalogSurface> c = {
      {"sphere", f_sphere, {0, 0, 0}, 2.0, {0, 0, 0}},
      {"ellipsoid", f_ellipsoid, {0, 0, 0}, 2.0, {0, 0, 0}},
      {"torus", f_torus, {0, 0, 0}, 2.0, {1, 0, 0}},
      {"double_torus", f_double_torus, {1, 0, 0}, 2.0, {1, 0, 0}},
      {"tanglecube",
       f_tanglecube,
       {0, 0, 0},
       4.0,
       {1.5811388300841898, 1.5811388300841898, 1.5811388300841898}},
      {"chair", f_chair, {0, 0, 0}, 7.0, {0, 0, 4.5}},
      {"blobs", f_blobs, {0, 0, 0}, 2.0, {0, 0, 0}},
      {"heart", f_heart, {0, 0, 0}, 2.0, {0, 0, 0}},
  };
  return c;
}

inline const CatalogSurface* find_surface(const std::string& name) {
  for (const auto& s : catalog())
    if (name == s.name) return &s;
  return nullptr;
}

inline std::string catalog_names() {
  std::string o;
  for (const auto& s : catalog()) o += (o.empty() ? "" : ", ") + std::string(s.name);
  return o;
}

}  // namespace bench
