// The shape of the seabed when it is a MuJoCo geom (`seabed=GEOMNAME` in <text name="water">,
// docs/environment.md): a plane (possibly tilted) or a height field, fixed in the world. The
// MuJoCo glue fills it at load from the geom's pose and data; the tether engine only asks for
// the surface's height and upward normal under a point. Free of MuJoCo; allocates nothing.
#ifndef MJTETHER_SRC_SEABED_H_
#define MJTETHER_SRC_SEABED_H_

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

namespace mjtether {

struct SeabedSurface {
  enum class Kind { kNone, kPlane, kHfield };
  Kind kind = Kind::kNone;
  // Plane: a point on it [m] and its unit normal (world, n.z() > 0).
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  // Height field, rotated about z only: centre [m] (world), heading (cos, sin) of its local
  // x axis, half sizes rx, ry [m], nrow x ncol heights [m] above the centre, row-major, rows
  // along local y from -ry, columns along local x from -rx (MuJoCo's hfield layout).
  double cos_yaw = 1, sin_yaw = 0;
  double rx = 0, ry = 0;
  int nrow = 0, ncol = 0;
  std::vector<double> height;  // [m] (nrow * ncol)

  bool declared() const { return kind != Kind::kNone; }

  // Height zs [m] of the surface above (x, y) and its upward unit normal n (world frame).
  // Plane: exact. Height field: the triangle of the cell under (x, y) (each cell split along
  // its diagonal from (row, col) to (row+1, col+1)), linear inside it; beyond the field's
  // edges the edge heights continue (clamped coordinates).
  void Under(double x, double y, double* zs, Eigen::Vector3d* n) const {
    if (kind == Kind::kPlane) {
      *zs = point.z() - (normal.x() * (x - point.x()) + normal.y() * (y - point.y())) / normal.z();
      *n = normal;
      return;
    }
    // Local coordinates of (x, y), then grid coordinates (column a, row b).
    const double dx = x - point.x(), dy = y - point.y();
    const double lx = cos_yaw * dx + sin_yaw * dy, ly = -sin_yaw * dx + cos_yaw * dy;
    const double sx = 2 * rx / (ncol - 1), sy = 2 * ry / (nrow - 1);  // [m] cell size
    const double a0 = (lx + rx) / sx, b0 = (ly + ry) / sy;
    const double a = std::clamp(a0, 0.0, ncol - 1.0), b = std::clamp(b0, 0.0, nrow - 1.0);
    const int c = std::min(static_cast<int>(a), ncol - 2),
              r = std::min(static_cast<int>(b), nrow - 2);
    const double fa = a - c, fb = b - r;
    const double h00 = height[r * ncol + c], h01 = height[r * ncol + c + 1];
    const double h10 = height[(r + 1) * ncol + c], h11 = height[(r + 1) * ncol + c + 1];
    // Lower triangle (fa >= fb): (0,0), (1,0), (1,1) in (a, b); upper: (0,0), (1,1), (0,1).
    double gx, gy;  // dh/da, dh/db per cell
    if (fa >= fb) {
      gx = h01 - h00;
      gy = h11 - h01;
    } else {
      gx = h11 - h10;
      gy = h10 - h00;
    }
    *zs = point.z() + h00 + gx * fa + gy * fb;
    // Local slope, rotated to the world; n = (-dh/dx, -dh/dy, 1) normalised.
    const double px = a0 == a ? gx / sx : 0, py = b0 == b ? gy / sy : 0;  // flat beyond edges
    const Eigen::Vector3d nl(-px, -py, 1);
    *n = Eigen::Vector3d(cos_yaw * nl.x() - sin_yaw * nl.y(), sin_yaw * nl.x() + cos_yaw * nl.y(),
                         1) /
         nl.norm();
  }

  // Height only [m].
  double HeightUnder(double x, double y) const {
    double zs;
    Eigen::Vector3d n;
    Under(x, y, &zs, &n);
    return zs;
  }
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_SEABED_H_
