// Tether-geom contact: which geoms a tether may touch, and the candidates of each step.
//
// Geometry is our own: the closest point between a segment (the tether's axis) and a geom,
// in the geom's frame, from closed forms for plane, sphere and capsule, and for box, cylinder
// and ellipsoid from a golden-section search along the segment of the geom's signed distance
// (convex along a line for a convex body, so the search finds the minimum); a height field's
// top surface gives one plane per segment from the triangles under it (HfieldSegment). Why not
// mjCOLLISIONFUNC: it needs geoms of the model for the segments, and returns nothing beyond
// its margin or for a segment deep inside; why not libccd/libfcl: a conversion per segment per
// step for shapes that have closed forms. See docs/contact.md.
#include "contact_glue.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>
#include <sstream>

#include "environment_glue.h"
#include "vehicle_glue.h"

namespace mjtether {
namespace {

using RowMat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

// Segments per broad-phase box.
constexpr int kChunk = 8;
// Golden-section iterations along a segment: 0.618^40 ~ 4e-9 of its length.
constexpr int kGoldenIterations = 40;

bool Supported(int type) {
  return type == mjGEOM_PLANE || type == mjGEOM_SPHERE || type == mjGEOM_CAPSULE ||
         type == mjGEOM_CYLINDER || type == mjGEOM_BOX || type == mjGEOM_ELLIPSOID ||
         type == mjGEOM_MESH || type == mjGEOM_HFIELD;
}

const char* TypeName(int type) {
  switch (type) {
    case mjGEOM_HFIELD:
      return "hfield";
    case mjGEOM_MESH:
      return "mesh";
    default:
      return "this type";
  }
}

// Closest point to p on the triangle (a, b, c) (Ericson, Real-Time Collision Detection, 2005,
// section 5.1.5: by the Voronoi regions of its corners, edges and face).
Vec3 ClosestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Signed distance of the local point p to a convex hull: inside, minus the distance to the
// nearest face plane (max of n.p - o, exact inside a convex body); outside, the distance to
// the nearest triangle that faces p (the closest point of a convex body is on one of them).
double HullDistance(const ConvexHull& h, const Vec3& p) {
  double inside = -INFINITY;
  const int n = static_cast<int>(h.normal.size());
  for (int f = 0; f < n; ++f) inside = std::max(inside, h.normal[f].dot(p) - h.offset[f]);
  if (inside <= 0) return inside;
  double best = INFINITY;
  for (int f = 0; f < n; ++f) {
    if (h.normal[f].dot(p) - h.offset[f] <= 0) continue;
    const Vec3 q = ClosestOnTriangle(p, h.corner[3 * f], h.corner[3 * f + 1], h.corner[3 * f + 2]);
    best = std::min(best, (p - q).squaredNorm());
  }
  return std::sqrt(best);
}

// Signed distance of the local point p to a box, cylinder, ellipsoid or mesh (hull) of MuJoCo
// size `sz` (box: half sizes; cylinder: radius, half length along z; ellipsoid: semi-axes).
double SignedDistance(int type, const double* sz, const ConvexHull* hull, const Vec3& p) {
  if (type == mjGEOM_MESH) return HullDistance(*hull, p);
  if (type == mjGEOM_BOX) {
    const Vec3 q = p.cwiseAbs() - Vec3(sz[0], sz[1], sz[2]);
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
  if (type == mjGEOM_CYLINDER) {
    const double dr = std::hypot(p.x(), p.y()) - sz[0], dz = std::abs(p.z()) - sz[1];
    return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0)) + std::min(std::max(dr, dz), 0.0);
  }
  // Ellipsoid: the first-order estimate k0 (k0 - 1)/k1 (exact on a sphere and on the axes).
  const Vec3 r(sz[0], sz[1], sz[2]);
  const double k0 = p.cwiseQuotient(r).norm();
  const double k1 = p.cwiseQuotient(r.cwiseProduct(r)).norm();
  if (k1 == 0) return -r.minCoeff();
  return k0 * (k0 - 1) / k1;
}

// Outward unit normal of a box, cylinder, ellipsoid or mesh at local p: the gradient of the
// signed distance by central differences (step small against the geom).
Vec3 Normal(int type, const double* sz, const ConvexHull* hull, const Vec3& p) {
  const double e = 1e-7 * (type == mjGEOM_MESH
                               ? hull->scale
                               : std::max({sz[0], sz[1], type == mjGEOM_CYLINDER ? sz[0] : sz[2]}));
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    Vec3 a = p, b = p;
    a[k] += e;
    b[k] -= e;
    g[k] = SignedDistance(type, sz, hull, a) - SignedDistance(type, sz, hull, b);
  }
  const double n = g.norm();
  return n > 0 ? Vec3(g / n) : Vec3::UnitZ();
}

// Height field (geom frame): distance of the local point p above the plane of the surface's
// triangle under it, (z - zs) n_z (docs/environment.md), and that triangle's upward normal;
// false if p is outside the field's footprint or below its base (no surface under it: the
// field is a finite block, its sides are not modelled).
bool HfieldGap(const ContactGeom& cg, const Vec3& p, double* gap, Vec3* normal) {
  const SeabedSurface& h = cg.hfield;
  if (std::abs(p.x()) > h.rx || std::abs(p.y()) > h.ry || p.z() < -cg.hfield_base) return false;
  double zs;
  h.Under(p.x(), p.y(), &zs, normal);
  *gap = (p.z() - zs) * normal->z();
  return true;
}

// Signed distance of the local point p to any supported geom (plane: its side z).
double PointDistance(int type, const double* sz, const ContactGeom& cg, const Vec3& p) {
  const ConvexHull* hull = &cg.hull;
  switch (type) {
    case mjGEOM_HFIELD: {
      double gap;
      Vec3 n;
      return HfieldGap(cg, p, &gap, &n) ? gap : INFINITY;
    }
    case mjGEOM_PLANE:
      return p.z();
    case mjGEOM_SPHERE:
      return p.norm() - sz[0];
    case mjGEOM_CAPSULE:
      return Vec3(p.x(), p.y(), p.z() - std::clamp(p.z(), -sz[1], sz[1])).norm() - sz[0];
    default:
      return SignedDistance(type, sz, hull, p);
  }
}

// Closest points of segments [a0, a1] and [b0, b1]: parameters s (on a), t (on b)
// (Ericson, Real-Time Collision Detection, 2005, section 5.1.9).
void SegmentSegment(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, double* s,
                    double* t) {
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double tiny = 1e-24;
  if (a <= tiny && e <= tiny) {
    *s = *t = 0;
    return;
  }
  if (a <= tiny) {
    *s = 0;
    *t = std::clamp(f / e, 0.0, 1.0);
    return;
  }
  const double c = d1.dot(r);
  if (e <= tiny) {
    *t = 0;
    *s = std::clamp(-c / a, 0.0, 1.0);
    return;
  }
  const double b = d1.dot(d2), denom = a * e - b * b;
  // Parallel segments: any s; take the middle of the overlap's start.
  *s = denom > 1e-12 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.5;
  *t = (b * *s + f) / e;
  if (*t < 0) {
    *t = 0;
    *s = std::clamp(-c / a, 0.0, 1.0);
  } else if (*t > 1) {
    *t = 1;
    *s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

// Closest point of the local segment [a, b] to the geom: its parameter s, the signed distance
// of the segment point to the geom's surface, the outward normal and the surface point.
struct Closest {
  double s, dist;
  Vec3 normal, surface;
};

Closest SegmentGeom(int type, const double* sz, const ConvexHull* hull, const Vec3& a,
                    const Vec3& b) {
  Closest c;
  auto from_center = [&](const Vec3& q, const Vec3& center, double radius) {
    const Vec3 r = q - center;
    const double len = r.norm();
    c.normal = len > 0 ? Vec3(r / len) : Vec3::UnitZ();
    c.dist = len - radius;
    c.surface = center + radius * c.normal;
  };
  if (type == mjGEOM_PLANE) {
    // Infinite plane z = 0 (MuJoCo's planes collide beyond their drawn size).
    const double dz = b.z() - a.z();
    c.s = std::abs(dz) <= 1e-9 * (a - b).norm() ? 0.5 : (dz > 0 ? 0.0 : 1.0);
    const Vec3 q = a + c.s * (b - a);
    c.dist = q.z();
    c.normal = Vec3::UnitZ();
    c.surface = Vec3(q.x(), q.y(), 0);
    return c;
  }
  if (type == mjGEOM_SPHERE) {
    const Vec3 d = b - a;
    const double dd = d.squaredNorm();
    c.s = dd > 0 ? std::clamp(-a.dot(d) / dd, 0.0, 1.0) : 0.0;
    from_center(a + c.s * d, Vec3::Zero(), sz[0]);
    return c;
  }
  if (type == mjGEOM_CAPSULE) {
    double t;
    const Vec3 b0(0, 0, -sz[1]), b1(0, 0, sz[1]);
    SegmentSegment(a, b, b0, b1, &c.s, &t);
    from_center(a + c.s * (b - a), b0 + t * (b1 - b0), sz[0]);
    return c;
  }
  // Box, cylinder, ellipsoid, mesh: golden section on the signed distance along the segment.
  constexpr double kInvPhi = 0.61803398874989484820;
  auto f = [&](double s) { return SignedDistance(type, sz, hull, a + s * (b - a)); };
  double lo = 0, hi = 1;
  double x1 = hi - kInvPhi * (hi - lo), x2 = lo + kInvPhi * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int it = 0; it < kGoldenIterations; ++it) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - kInvPhi * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + kInvPhi * (hi - lo);
      f2 = f(x2);
    }
  }
  // The ends are candidates too (the search brackets an interior minimum).
  c.s = 0.5 * (lo + hi);
  double best = f(c.s);
  for (double end : {0.0, 1.0}) {
    const double fe = f(end);
    if (fe < best) best = fe, c.s = end;
  }
  const Vec3 q = a + c.s * (b - a);
  c.dist = best;
  c.normal = Normal(type, sz, hull, q);
  c.surface = q - best * c.normal;
  return c;
}

// Height field: one plane for the local segment [a, b] (docs/contact.md, "Height fields").
// The surface under the part of the segment above the field's footprint is sampled at half the
// smaller cell size (at most 65 samples, both ends of that part included; the triangle under
// each sample, HfieldGap). The plane contains the secant between the surface points under the
// two ends of that part, S0 and S1, tilted across it as the samples' mean normal, and is lifted
// along its normal until no sample of the surface is above it: on a ramp it is the ramp; in a
// hollow the nodes' gaps are the surface's; over a crest it is the plane a straight segment
// rests on. It moves continuously with the nodes (no switching between triangles, which made a
// tether resting on a curved field chatter). Returns the plane's point and normal, the sample
// whose axis point is lowest against it and that gap; false if no part of the segment is over
// the field.
bool HfieldSegment(const ContactGeom& cg, const Vec3& a, const Vec3& b, double L0, Closest* c) {
  const SeabedSurface& h = cg.hfield;
  // The segment's parameter range over the footprint |x| <= rx, |y| <= ry (slab clipping).
  double lo = 0, hi = 1;
  const Vec3 d = b - a;
  const double half[2] = {h.rx, h.ry};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0) {
      if (std::abs(a[k]) > half[k]) return false;
      continue;
    }
    double t0 = (-half[k] - a[k]) / d[k], t1 = (half[k] - a[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  if (!(lo <= hi)) return false;
  // Samples from the rest length (not the current span), so that their number does not jump.
  const double cell = std::min(2 * h.rx / (h.ncol - 1), 2 * h.ry / (h.nrow - 1));
  const int n = std::clamp(static_cast<int>(std::ceil((hi - lo) * L0 / (0.5 * cell))), 1, 64);
  // Each sample once: its axis point q and the surface point S under it (on the stack: this
  // runs per segment per step).
  constexpr int kMaxSamples = 65;
  Vec3 q[kMaxSamples], S[kMaxSamples];
  double at[kMaxSamples];  // the sample's parameter along [a, b]
  Vec3 mean = Vec3::Zero();
  int count = 0;
  for (int k = 0; k <= n; ++k) {
    const double sk = lo + (hi - lo) * k / n;
    const Vec3 qk = a + sk * d;
    double gap;
    Vec3 normal;
    if (!HfieldGap(cg, qk, &gap, &normal)) continue;
    q[count] = qk;
    S[count] = Vec3(qk.x(), qk.y(), qk.z() - gap / normal.z());
    at[count] = sk;
    mean += normal;
    ++count;
  }
  if (count == 0) return false;
  const Vec3& S0 = S[0];
  // The plane's normal: the mean normal without its component along the secant.
  Vec3 nrm = mean.normalized();
  const Vec3 t = S[count - 1] - S0;
  if (t.squaredNorm() > 1e-24) {
    const Vec3 th = t.normalized();
    const Vec3 across = nrm - nrm.dot(th) * th;
    if (across.z() > 0 && across.norm() > 1e-6) nrm = across.normalized();
  }
  // Lifted over every sample of the surface; the lowest axis point against it.
  double lift = 0;
  for (int k = 0; k < count; ++k) lift = std::max(lift, nrm.dot(S[k] - S0));
  c->dist = INFINITY;
  for (int k = 0; k < count; ++k) {
    const double gap = nrm.dot(q[k] - S0) - lift;
    if (gap < c->dist) {
      c->dist = gap;
      c->s = at[k];
      c->surface = q[k] - gap * nrm;
    }
  }
  c->normal = nrm;
  return true;
}

// The geom's thinnest half-size [m]: the radius (and a cylinder's half-length), a box's or an
// ellipsoid's smallest half-size, a mesh hull's depth from its corners' centroid to its nearest
// face, a height field's smaller cell; 0 for a plane.
double ThinnestHalfSize(const mjModel* m, const ContactGeom& cg) {
  const int g = cg.geom;
  const double* sz = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE:
    case mjGEOM_CAPSULE:
      return sz[0];
    case mjGEOM_CYLINDER:
      return std::min(sz[0], sz[1]);
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID:
      return std::min({sz[0], sz[1], sz[2]});
    case mjGEOM_MESH: {
      Vec3 c = Vec3::Zero();
      for (const Vec3& p : cg.hull.corner) c += p;
      c /= std::max<size_t>(1, cg.hull.corner.size());
      double thin = INFINITY;
      for (size_t f = 0; f < cg.hull.normal.size(); ++f) {
        thin = std::min(thin, cg.hull.offset[f] - cg.hull.normal[f].dot(c));
      }
      return std::isfinite(thin) ? std::max(thin, 0.0) : 0;
    }
    case mjGEOM_HFIELD:
      return std::min(2 * cg.hfield.rx / (cg.hfield.ncol - 1),
                      2 * cg.hfield.ry / (cg.hfield.nrow - 1));
    default:
      return 0;
  }
}

// The convex hull of mesh `mesh` in its geom's frame (MuJoCo stores a mesh's vertices in
// the frame of its inertia, which is the geom's). Its triangles from the convex graph MuJoCo
// keeps for collisions (mesh_graph: numvert, numface, vert_edgeadr[numvert],
// vert_globalid[numvert], edge_localid[numvert + 3 numface], face_globalid[3 numface]), or,
// for a mesh without one, the mesh's own triangles (taken as convex). Each plane is turned
// outward: the vertices' centroid on its inner side.
void MakeHull(const mjModel* m, int mesh, ConvexHull* h) {
  const float* vert = m->mesh_vert + 3 * m->mesh_vertadr[mesh];
  const int nv = m->mesh_vertnum[mesh];
  const int* faces;
  int nf;
  if (m->mesh_graphadr[mesh] >= 0) {
    const int* graph = m->mesh_graph + m->mesh_graphadr[mesh];
    const int gv = graph[0];
    nf = graph[1];
    faces = graph + 2 + 3 * gv + 3 * nf;
  } else {
    nf = m->mesh_facenum[mesh];
    faces = m->mesh_face + 3 * m->mesh_faceadr[mesh];
  }
  auto vertex = [&](int i) { return Vec3(vert[3 * i], vert[3 * i + 1], vert[3 * i + 2]); };
  Vec3 centroid = Vec3::Zero();
  for (int i = 0; i < nv; ++i) centroid += vertex(i);
  centroid /= std::max(nv, 1);
  double scale = 0;
  for (int i = 0; i < nv; ++i) scale = std::max(scale, (vertex(i) - centroid).norm());
  h->scale = scale > 0 ? scale : 1;
  for (int f = 0; f < nf; ++f) {
    const Vec3 a = vertex(faces[3 * f]), b = vertex(faces[3 * f + 1]), c = vertex(faces[3 * f + 2]);
    Vec3 n = (b - a).cross(c - a);
    // Degenerate triangles carry no plane.
    if (!(n.norm() > 1e-12 * h->scale * h->scale)) continue;
    n.normalize();
    if (n.dot(centroid - a) > 0) n = -n;
    h->corner.insert(h->corner.end(), {a, b, c});
    h->normal.push_back(n);
    h->offset.push_back(n.dot(a));
  }
}

}  // namespace

bool ResolveContactGeoms(const mjModel* m, const std::string& spec, const int site[2],
                         const Tether& tether, TetherContacts* out,
                         std::vector<std::string>* warnings, std::string* error) {
  std::vector<int> geoms;
  // The seabed geom (seabed=GEOMNAME) has the seabed's force already.
  const std::string& seabed_name = tether.env().water.seabed_geom;
  const int seabed = seabed_name.empty() ? -1 : mj_name2id(m, mjOBJ_GEOM, seabed_name.c_str());
  if (spec == "all") {
    // Every geom that would collide with a geom of contype 1 and conaffinity 1.
    for (int g = 0; g < m->ngeom; ++g) {
      if (!((m->geom_contype[g] & 1) || (m->geom_conaffinity[g] & 1))) continue;
      if (g == seabed) continue;
      if (!Supported(m->geom_type[g])) {
        const char* name = m->names + m->name_geomadr[g];
        std::ostringstream s;
        s << "key 'contact' = all: geom " << (name[0] ? name : std::to_string(g).c_str())
          << " is a " << TypeName(m->geom_type[g])
          << ", which tether contact does not support yet; it is left out";
        warnings->push_back(s.str());
        continue;
      }
      geoms.push_back(g);
    }
  } else {
    std::stringstream list(spec);
    std::string name;
    while (std::getline(list, name, ',')) {
      const int g = mj_name2id(m, mjOBJ_GEOM, name.c_str());
      const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
      if (g < 0 && b < 0) {
        *error = "key 'contact': no geom or body named '" + name + "' in the model";
        return false;
      }
      if (g >= 0) {
        if (g == seabed) {
          *error = "key 'contact': geom '" + name +
                   "' is the seabed (seabed=" + name +
                   " in <text name=\"water\">), which the seabed force already acts on; "
                   "leave it out";
          return false;
        }
        if (!Supported(m->geom_type[g])) {
          *error = "key 'contact': geom '" + name + "' is a " + TypeName(m->geom_type[g]) +
                   "; supported: plane, sphere, capsule, cylinder, box, ellipsoid, mesh, "
                   "hfield";
          return false;
        }
        geoms.push_back(g);
      } else {
        for (int k = 0; k < m->body_geomnum[b]; ++k) {
          const int gk = m->body_geomadr[b] + k;
          if (gk == seabed) continue;
          if (Supported(m->geom_type[gk])) {
            geoms.push_back(gk);
          } else {
            warnings->push_back("key 'contact': body '" + name + "' has a " +
                                TypeName(m->geom_type[gk]) +
                                " geom, which tether contact does not support yet; it is left "
                                "out");
          }
        }
      }
    }
  }
  std::sort(geoms.begin(), geoms.end());
  geoms.erase(std::unique(geoms.begin(), geoms.end()), geoms.end());
  out->geoms.clear();
  for (int g : geoms) {
    ContactGeom cg;
    cg.geom = g;
    if (m->geom_type[g] == mjGEOM_MESH) MakeHull(m, m->geom_dataid[g], &cg.hull);
    if (m->geom_type[g] == mjGEOM_HFIELD) {
      const int h = m->geom_dataid[g];
      if (!HfieldSurface(m, h, &cg.hfield)) {
        const char* gname = m->names + m->name_geomadr[g];
        *error = "key 'contact': hfield geom '" +
                 std::string(gname[0] ? gname : std::to_string(g)) +
                 "' has fewer than 2 x 2 heights";
        return false;
      }
      cg.hfield_base = m->hfield_size[4 * h + 3];
      cg.hfield_top = m->hfield_size[4 * h + 2];
      cg.hfield_rbound = Vec3(cg.hfield.rx, cg.hfield.ry,
                              std::max(cg.hfield_top, cg.hfield_base)).norm();
    }
    cg.max_ahead = 0.25 * ThinnestHalfSize(m, cg);
    // A geom on an end's body is that end's own when the site is inside it or within
    // rho = L0 + d of its surface (the tether starts against it): its segments skip it over the
    // arc that leaves it, the site's depth in it plus rho. Other geoms of that body (a part of
    // the vehicle away from the attachment, scenery on the world body) are never skipped.
    const double rho = tether.rest_segment_length() + tether.params().diameter;
    for (int end = 0; end < 2; ++end) {
      const int s = site[end];
      if (s < 0 || m->site_bodyid[s] != m->geom_bodyid[g]) continue;
      // The site in the geom's frame (both are fixed in the body's frame).
      mjtNum rel[3], local[3], qinv[4];
      mju_sub3(rel, m->site_pos + 3 * s, m->geom_pos + 3 * g);
      mju_negQuat(qinv, m->geom_quat + 4 * g);
      mju_rotVecQuat(local, rel, qinv);
      const double depth = -PointDistance(m->geom_type[g], m->geom_size + 3 * g, cg,
                                          Vec3(local[0], local[1], local[2]));
      if (depth > -rho) cg.skip[end] = std::max(0.0, depth) + rho;
    }
    out->geoms.push_back(cg);
  }
  out->capacity = 4 * tether.segments() + 16;
  return true;
}

int FindContacts(const mjModel* m, const mjData* d, const TetherContacts& tc, const Tether& tether,
                 const double* xp, const double* vp, double dt, double* boxes, ContactPoint* out,
                 int capacity, int* dropped) {
  const int N = tether.segments();
  ConstNodes x(xp, 3, N + 1), v(vp, 3, N + 1);
  const double r = 0.5 * tether.params().diameter;
  const double L0 = tether.rest_segment_length();
  // The margin covers what the tether and a body can close in two steps.
  double vmax = 0;
  for (int i = 0; i <= N; ++i) vmax = std::max(vmax, v.col(i).norm());
  const double reach = r + 2 * dt * vmax + 1e-3 * L0;
  // How far ahead the planes of curved geoms are found: the step's end, where the
  // backward-Euler family (implicit, bdf2, implicit2) evaluates the contact force. The explicit
  // ones (explicit, rk4) evaluate it through the step and keep the planes of its start (their
  // middle of the step cancelled their drag too, but with friction the wrap's kinetic energy
  // rose 2.4x and its mu_eff fell 3 %: docs/contact.md, "Frozen planes").
  const Integrator integrator = tether.params().integrator;
  const double ahead =
      integrator == Integrator::kExplicit || integrator == Integrator::kRK4 ? 0.0 : dt;
  int count = 0;
  *dropped = 0;
  // Boxes of 8 segments (lo, hi: 6 doubles each) and of the whole tether, once per call.
  const int chunks = (N + kChunk - 1) / kChunk;
  Vec3 all_lo = x.col(0), all_hi = x.col(0);
  for (int c = 0; c < chunks; ++c) {
    const int c0 = c * kChunk, c1 = std::min(N, c0 + kChunk);
    const Vec3 lo = x.middleCols(c0, c1 - c0 + 1).rowwise().minCoeff();
    const Vec3 hi = x.middleCols(c0, c1 - c0 + 1).rowwise().maxCoeff();
    for (int k = 0; k < 3; ++k) boxes[6 * c + k] = lo[k], boxes[6 * c + 3 + k] = hi[k];
    all_lo = all_lo.cwiseMin(lo);
    all_hi = all_hi.cwiseMax(hi);
  }
  auto apart = [](const Vec3& p, const Vec3& lo, const Vec3& hi, double bound) {
    return ((p.array() < lo.array() - bound) || (p.array() > hi.array() + bound)).any();
  };
  for (const ContactGeom& cg : tc.geoms) {
    const int g = cg.geom;
    const int type = m->geom_type[g];
    const Vec3 pos(d->geom_xpos + 3 * g);
    const Eigen::Map<const RowMat3> R(d->geom_xmat + 9 * g);
    const double* sz = m->geom_size + 3 * g;
    const bool plane = type == mjGEOM_PLANE;
    // Velocity of the geom's body: twist at the geom's centre (a mocap body moved by a
    // motion: declaration has its prescribed velocity; another mocap body none).
    // Geoms welded to the world (scenery) have none, without asking.
    const int body = m->geom_bodyid[g];
    Vec3 w = Vec3::Zero(), vg = Vec3::Zero();
    if (m->body_mocapid[body] >= 0) {
      PrescribedVelocity(m, d, body, &vg);
    } else if (m->body_weldid[body] != 0) {
      mjtNum twist[6];
      mj_objectVelocity(m, d, mjOBJ_GEOM, g, twist, 0);
      w = Vec3(twist[0], twist[1], twist[2]);
      vg = Vec3(twist[3], twist[4], twist[5]);
    }
    // MuJoCo gives an hfield no bounding radius (0): ours, and its box in its frame
    // (footprint, base to top), which is the broad phase of an hfield instead of the sphere.
    const bool hfield = type == mjGEOM_HFIELD;
    const double rbound = hfield ? cg.hfield_rbound : m->geom_rbound[g];
    const double margin = reach + 2 * dt * (vg.norm() + w.norm() * rbound);
    const double bound = rbound + margin;
    const Vec3 field_lo(-cg.hfield.rx - margin, -cg.hfield.ry - margin, -cg.hfield_base - margin),
        field_hi(cg.hfield.rx + margin, cg.hfield.ry + margin, cg.hfield_top + margin);
    // A world box (lo, hi) is apart from the field's box: its box in the field's frame
    // (centre R^T (c - pos), half sizes |R^T| e) does not overlap.
    auto off_field = [&](const Vec3& lo, const Vec3& hi) {
      const Vec3 c = R.transpose() * (0.5 * (lo + hi) - pos);
      const Vec3 e = R.transpose().cwiseAbs() * (0.5 * (hi - lo));
      return ((c + e).array() < field_lo.array() || (c - e).array() > field_hi.array()).any();
    };
    if (hfield ? off_field(all_lo, all_hi) : !plane && apart(pos, all_lo, all_hi, bound)) {
      continue;
    }
    for (int c0 = 0; c0 < N; c0 += kChunk) {
      const int c1 = std::min(N, c0 + kChunk);
      const double* box = boxes + 6 * (c0 / kChunk);
      // Broad phase: the chunk's box against the geom's bounding sphere (a plane: its
      // signed distance against the chunk's lowest node).
      if (plane) {
        const Vec3 nrm = R.col(2);
        double lowest = INFINITY;
        for (int i = c0; i <= c1; ++i) lowest = std::min(lowest, nrm.dot(x.col(i) - pos));
        if (lowest > margin) continue;
      } else if (hfield ? off_field(Vec3(box), Vec3(box + 3))
                        : apart(pos, Vec3(box), Vec3(box + 3), bound)) {
        continue;
      }
      for (int j = c0; j < c1; ++j) {
        if (j * L0 < cg.skip[0] || (N - j - 1) * L0 < cg.skip[1]) continue;
        const Vec3 a = x.col(j), b = x.col(j + 1);
        if (!plane && !hfield) {
          if (apart(pos, a.cwiseMin(b), a.cwiseMax(b), bound)) continue;
        }
        // Narrow phase in the geom's frame.
        const Vec3 la = R.transpose() * (a - pos), lb = R.transpose() * (b - pos);
        // The plane of a curved geom is found where the segment will be, relative to the
        // body, when the integrator evaluates the force (docs/contact.md, "Frozen planes").
        // At most cg.max_ahead, so that a fast segment's prediction does not cross the geom.
        auto ahead_of = [&](const Vec3& p, const Vec3& vp) {
          Vec3 step = ahead * (vp - vg - w.cross(p - pos));
          const double len = step.norm();
          if (len > cg.max_ahead) step *= cg.max_ahead / len;
          return Vec3(R.transpose() * (p + step - pos));
        };
        const Vec3 pa = ahead_of(a, v.col(j)), pb = ahead_of(b, v.col(j + 1));
        Closest c;
        if (hfield) {
          // The segment's box against the field's, in its frame, first.
          if (((la.cwiseMax(lb).array() < field_lo.array()) ||
               (la.cwiseMin(lb).array() > field_hi.array()))
                  .any()) {
            continue;
          }
          if (!HfieldSegment(cg, pa, pb, L0, &c)) continue;
        } else {
          c = SegmentGeom(type, sz, &cg.hull, plane ? la : pa, plane ? lb : pb);
        }
        // The gap of the segment as it is against that plane (linear along it: its lower
        // end's); a supporting plane of a convex geom is never farther than the geom.
        if (!plane) c.dist = std::min(c.normal.dot(la - c.surface), c.normal.dot(lb - c.surface));
        if (!(c.dist < margin)) continue;
        if (count == capacity) {
          ++*dropped;
          continue;
        }
        ContactPoint& cp = *new (out + count++) ContactPoint();
        cp.segment = j;
        cp.s = c.s;
        cp.point = pos + R * c.surface;
        cp.normal = R * c.normal;
        cp.velocity = vg + w.cross(cp.point - pos);
        cp.impulse.setZero();
        cp.impulse_b.setZero();
        cp.stage.setZero();
        cp.stage_b.setZero();
        cp.tag = body;
      }
    }
  }
  return count;
}

}  // namespace mjtether
