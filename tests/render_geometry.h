// Where a world point lands in a rendered frame, written from the GL camera's fields (not with
// the renderer's own projection, which is what these tests check). Shared by render_test.cc,
// render_framing_test.cc, gallery_framing_test.cc and viewer_test.cc.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>

namespace mjtether::test_util {

// Pixel (column, row from the bottom) where p projects through the GL camera c in a W x H
// viewport, as mjr_render sets up OpenGL: a look-at view from pos along forward with up, and a
// frustum [center -/+ half width] x [bottom, top] at the near plane, its width from the
// viewport's aspect ratio.
inline std::array<double, 2> ProjectGl(const mjvGLCamera& c, int W, int H, const double* p) {
  double v[3], right[3];
  for (int i = 0; i < 3; ++i) v[i] = p[i] - c.pos[i];
  const double f[3] = {c.forward[0], c.forward[1], c.forward[2]};
  const double u[3] = {c.up[0], c.up[1], c.up[2]};
  mju_cross(right, f, u);
  const double z = mju_dot3(v, f);
  const double xn = c.frustum_near * mju_dot3(v, right) / z;
  const double yn = c.frustum_near * mju_dot3(v, u) / z;
  const double half_w = 0.5 * W / H * (c.frustum_top - c.frustum_bottom);
  const double left = c.frustum_center - half_w;
  return {W * (xn - left) / (2 * half_w),
          H * (yn - c.frustum_bottom) / (c.frustum_top - c.frustum_bottom)};
}

// The camera of a mono image: the average of the scene's two eyes (each is offset by half the
// inter-pupillary distance).
inline mjvGLCamera MonoCamera(const mjvScene& scn) {
  return mjv_averageCamera(&scn.camera[0], &scn.camera[1]);
}

// Pixel where p projects through a scene's mono camera.
inline std::array<double, 2> ProjectScene(const mjvScene& scn, int W, int H, const double* p) {
  return ProjectGl(MonoCamera(scn), W, H, p);
}

// Box bounding the projections of the corners of body b's visible geoms (groups 0-2, not
// transparent): {xmin, ymin, xmax, ymax}. `project` maps a world point to a pixel.
template <class Projection>
std::array<double, 4> BodyBox(const mjModel* m, const mjData* d, int b, Projection project) {
  std::array<double, 4> box = {1e300, 1e300, -1e300, -1e300};
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] != b || m->geom_group[g] > 2 || m->geom_rgba[4 * g + 3] == 0) continue;
    const double* s = m->geom_size + 3 * g;
    double e[3] = {s[0], s[1], s[2]};
    if (m->geom_type[g] == mjGEOM_SPHERE) e[1] = e[2] = s[0];
    if (m->geom_type[g] == mjGEOM_CYLINDER) e[1] = s[0], e[2] = s[1];
    if (m->geom_type[g] == mjGEOM_CAPSULE) e[1] = s[0], e[2] = s[0] + s[1];
    for (int corner = 0; corner < 8; ++corner) {
      double local[3], world[3];
      for (int i = 0; i < 3; ++i) local[i] = (corner >> i & 1 ? 1 : -1) * e[i];
      mju_rotVecMat(world, local, d->geom_xmat + 9 * g);
      mju_addTo3(world, d->geom_xpos + 3 * g);
      const std::array<double, 2> px = project(world);
      box[0] = std::min(box[0], px[0]), box[1] = std::min(box[1], px[1]);
      box[2] = std::max(box[2], px[0]), box[3] = std::max(box[3], px[1]);
    }
  }
  return box;
}

}  // namespace mjtether::test_util
