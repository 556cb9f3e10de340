#include "environment_glue.h"

#include <cmath>
#include <optional>
#include <sstream>

namespace mjtether {
namespace {

// The seabed surface from a plane or hfield geom fixed in the world, at qpos0.
bool SeabedFromGeom(const mjModel* m, Water* w, std::string* error) {
  const std::string& name = w->seabed_geom;
  auto fail = [&](const std::string& why) {
    *error = "key 'seabed' = '" + name + "': " + why;
    return false;
  };
  const int g = mj_name2id(m, mjOBJ_GEOM, name.c_str());
  if (g < 0) return fail("no geom of that name (give a plane or hfield geom, or a height [m])");
  const int type = m->geom_type[g];
  if (type != mjGEOM_PLANE && type != mjGEOM_HFIELD) {
    return fail("the geom must be a plane or an hfield");
  }
  const int body = m->geom_bodyid[g];
  if (m->body_weldid[body] != 0 || m->body_mocapid[body] >= 0) {
    return fail(
        "the geom must be fixed in the world (on the world body or a body without "
        "joints, not a mocap body)");
  }
  // The geom's pose at qpos0 (it never moves).
  mjData* d = mj_makeData(m);
  if (!d) return fail("cannot allocate mjData to place the geom");
  mj_kinematics(m, d);
  const Eigen::Vector3d pos(d->geom_xpos + 3 * g);
  const mjtNum* R = d->geom_xmat + 9 * g;  // row-major, columns are the geom's axes
  const Eigen::Vector3d ex(R[0], R[3], R[6]), ez(R[2], R[5], R[8]);
  mj_deleteData(d);
  SeabedSurface& s = w->surface;
  s.point = pos;
  if (type == mjGEOM_PLANE) {
    // Steeper than 80 degrees is a wall, not a seabed (the height under a point is undefined
    // at 90).
    if (!(ez.z() >= std::cos(80 * M_PI / 180))) {
      std::ostringstream o;
      o << "the plane's normal (" << ez.x() << ", " << ez.y() << ", " << ez.z()
        << ") must point up, at most 80 degrees from +z";
      return fail(o.str());
    }
    s.kind = SeabedSurface::Kind::kPlane;
    s.normal = ez.normalized();
    return true;
  }
  if (!(ez.z() >= 1 - 1e-9)) {
    return fail("an hfield seabed may be turned about z only (its z axis vertical)");
  }
  if (!HfieldSurface(m, m->geom_dataid[g], &s)) {
    return fail("the hfield needs at least 2 x 2 heights");
  }
  s.point = pos;
  s.cos_yaw = ex.x() / std::hypot(ex.x(), ex.y());
  s.sin_yaw = ex.y() / std::hypot(ex.x(), ex.y());
  return true;
}

}  // namespace

bool HfieldSurface(const mjModel* m, int h, SeabedSurface* s) {
  s->kind = SeabedSurface::Kind::kHfield;
  s->point.setZero();
  s->cos_yaw = 1;
  s->sin_yaw = 0;
  s->rx = m->hfield_size[4 * h];
  s->ry = m->hfield_size[4 * h + 1];
  s->nrow = m->hfield_nrow[h];
  s->ncol = m->hfield_ncol[h];
  if (s->nrow < 2 || s->ncol < 2) return false;
  // MuJoCo's heights are normalised to [0, 1] and scaled by the elevation size[2].
  const float* data = m->hfield_data + m->hfield_adr[h];
  s->height.resize(static_cast<size_t>(s->nrow) * s->ncol);
  for (size_t i = 0; i < s->height.size(); ++i) {
    s->height[i] = data[i] * m->hfield_size[4 * h + 2];
  }
  return true;
}

bool ResolveWater(const mjModel* m, const std::string& source, Water* w, std::string* error) {
  if (!w->current_profile.empty()) {
    const std::string& file = w->current_profile;
    const size_t slash = source.find_last_of('/');
    const std::string path =
        file[0] == '/' || slash == std::string::npos ? file : source.substr(0, slash + 1) + file;
    std::optional<CurrentProfile> profile = ReadCurrentProfile(path, error);
    if (!profile) return false;
    w->profile = std::move(*profile);
  }
  if (!w->seabed_geom.empty() && !SeabedFromGeom(m, w, error)) return false;
  return true;
}

std::string SeabedDescription(const Water& w) {
  std::ostringstream o;
  if (w.surface.declared()) {
    o << "'seabed' = geom '" << w.seabed_geom << "'";
  } else {
    o << "'seabed' = " << w.seabed << " m";
  }
  return o.str();
}

}  // namespace mjtether
