// The node and tension overlay (RenderOptions::overlay, the viewer's O key): each node of every
// tether as a white sphere, and the tension of every k-th segment as a label beside its middle,
// so that at most about 8 labels per tether are drawn.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "mjtether.h"
#include "render.h"

namespace mjtether::render {

namespace {

constexpr float kNodeColour[4] = {1.0f, 1.0f, 1.0f, 1.0f};
constexpr int kMaxLabels = 8;  // per tether

}  // namespace

// The spheres: decor geoms added to the scene before it is rendered.
void Renderer::DrawOverlay(const mjModel* m, const mjData* d, double D) {
  // A decor geom appended to the scene; null when the scene is full.
  auto add = [this](int type, const mjtNum* size, const mjtNum* pos) -> mjvGeom* {
    if (scn_.ngeom >= scn_.maxgeom) return nullptr;
    mjvGeom* g = scn_.geoms + scn_.ngeom;
    mjv_initGeom(g, type, size, pos, nullptr, kNodeColour);
    g->category = mjCAT_DECOR;
    g->objtype = mjOBJ_UNKNOWN;
    g->objid = -1;
    g->segid = scn_.ngeom;
    ++scn_.ngeom;
    return g;
  };
  for (int k = 0; k < TetherCount(m); ++k) {
    const Tether& t = *GetTether(m, k);
    const double* x = NodePositions(m, d, k);
    if (!x) continue;
    // [m] twice the drawn tether's radius (its own, or 1/250 of the camera distance D).
    const double r = 2 * std::max(0.5 * t.params().diameter, D / 250.0);
    const mjtNum size[3] = {r, r, r};
    for (int i = 0; i < t.nodes(); ++i) add(mjGEOM_SPHERE, size, x + 3 * i);
  }
}

// The labels: 2-D text drawn over the rendered scene (no depth test, so the spheres and
// capsules around a segment never hide it), at the projection of each labelled segment's
// middle through the scene's camera.
void Renderer::DrawOverlayLabels(const mjModel* m, const mjData* d) {
  const mjvGLCamera c = mjv_averageCamera(&scn_.camera[0], &scn_.camera[1]);
  const double half_w = 0.5 * opt_.width / opt_.height * (c.frustum_top - c.frustum_bottom);
  const double left = c.frustum_center - half_w;
  mjtNum right[3];
  const mjtNum forward[3] = {c.forward[0], c.forward[1], c.forward[2]};
  const mjtNum up[3] = {c.up[0], c.up[1], c.up[2]};
  mju_cross(right, forward, up);
  std::vector<double> T;
  char text[32];
  for (int k = 0; k < TetherCount(m); ++k) {
    const Tether& t = *GetTether(m, k);
    const double* x = NodePositions(m, d, k);
    if (!x) continue;
    T.resize(t.segments());
    GetTensions(m, d, k, T.data());
    const int every = std::max(1, (t.segments() + kMaxLabels - 1) / kMaxLabels);
    for (int j = every / 2; j < t.segments(); j += every) {
      mjtNum v[3];  // segment j runs from node j to node j + 1
      for (int i = 0; i < 3; ++i) v[i] = 0.5 * (x[3 * j + i] + x[3 * j + 3 + i]) - c.pos[i];
      const double z = mju_dot3(v, forward);
      if (!(z > c.frustum_near)) continue;  // behind the camera
      // Relative viewport coordinates of the point, then a little right of it.
      const double u = (c.frustum_near * mju_dot3(v, right) / z - left) / (2 * half_w);
      const double w = (c.frustum_near * mju_dot3(v, up) / z - c.frustum_bottom) /
                       (c.frustum_top - c.frustum_bottom);
      if (u < 0 || u > 1 || w < 0 || w > 1) continue;
      std::snprintf(text, sizeof(text), T[j] >= 100 ? "%.0f N" : "%.3g N", T[j]);
      mjr_text(mjFONT_SHADOW, text, &con_, static_cast<float>(u + 0.01), static_cast<float>(w), 1,
               1, 1);
    }
  }
}

}  // namespace mjtether::render
