// Off-screen rendering of tethered scenes (see render.h).
#include "render.h"

#include <GL/osmesa.h>
#include <dlfcn.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "mjtether.h"

namespace mjtether::render {

// libOSMesa is opened when the first Renderer is created rather than linked: it loads LLVM,
// which would add about 50 ms to the start of every mjtether command, rendering or not. It is
// opened with RTLD_GLOBAL so that MuJoCo's GL loader finds OSMesaGetProcAddress in the process.
struct OsMesaApi {
  decltype(&OSMesaCreateContextExt) CreateContextExt = nullptr;
  decltype(&OSMesaMakeCurrent) MakeCurrent = nullptr;
  decltype(&OSMesaDestroyContext) DestroyContext = nullptr;
  // The fixed-function calls that draw the water behind the scene.
  decltype(&glPushAttrib) PushAttrib = nullptr;
  decltype(&glPopAttrib) PopAttrib = nullptr;
  decltype(&glDisable) Disable = nullptr;
  decltype(&glEnable) Enable = nullptr;
  decltype(&glDepthFunc) DepthFunc = nullptr;
  decltype(&glDepthMask) DepthMask = nullptr;
  decltype(&glViewport) Viewport = nullptr;
  decltype(&glMatrixMode) MatrixMode = nullptr;
  decltype(&glPushMatrix) PushMatrix = nullptr;
  decltype(&glPopMatrix) PopMatrix = nullptr;
  decltype(&glLoadIdentity) LoadIdentity = nullptr;
  decltype(&glShadeModel) ShadeModel = nullptr;
  decltype(&glBegin) Begin = nullptr;
  decltype(&glEnd) End = nullptr;
  decltype(&glColor3fv) Color3fv = nullptr;
  decltype(&glVertex3f) Vertex3f = nullptr;
};

namespace {

constexpr double kPi = 3.14159265358979323846;

// Fills api's GL functions (the fixed-function calls of DrawWater) from lookup(name). False,
// with *error naming the first missing one, if one is missing.
template <class Lookup>
bool LoadGlFunctions(OsMesaApi* api, Lookup lookup, std::string* error) {
  bool ok = true;
  auto get = [&](auto& f, const char* symbol) {
    f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(lookup(symbol));
    if (!f && ok) {
      ok = false;
      *error = std::string("has no ") + symbol;
    }
  };
  get(api->PushAttrib, "glPushAttrib");
  get(api->PopAttrib, "glPopAttrib");
  get(api->Disable, "glDisable");
  get(api->Enable, "glEnable");
  get(api->DepthFunc, "glDepthFunc");
  get(api->DepthMask, "glDepthMask");
  get(api->Viewport, "glViewport");
  get(api->MatrixMode, "glMatrixMode");
  get(api->PushMatrix, "glPushMatrix");
  get(api->PopMatrix, "glPopMatrix");
  get(api->LoadIdentity, "glLoadIdentity");
  get(api->ShadeModel, "glShadeModel");
  get(api->Begin, "glBegin");
  get(api->End, "glEnd");
  get(api->Color3fv, "glColor3fv");
  get(api->Vertex3f, "glVertex3f");
  return ok;
}

// The OSMesa functions, or nullptr with *error set if the library cannot be opened.
const OsMesaApi* OsMesa(std::string* error) {
  static OsMesaApi api;
  static std::string load_error;
  static std::once_flag once;
  std::call_once(once, [] {
    void* lib = nullptr;
    for (const char* name : {"libOSMesa.so.8", "libOSMesa.so"}) {
      if ((lib = dlopen(name, RTLD_NOW | RTLD_GLOBAL))) break;
    }
    if (!lib) {
      const char* why = dlerror();
      load_error = std::string("OSMesa: cannot open libOSMesa.so.8 (install libosmesa6): ") +
                   (why ? why : "");
      return;
    }
    bool ok = true;
    auto get = [&](auto& f, const char* symbol) {
      f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(dlsym(lib, symbol));
      if (!f) {
        ok = false;
        load_error = std::string("OSMesa: libOSMesa has no ") + symbol;
      }
    };
    get(api.CreateContextExt, "OSMesaCreateContextExt");
    get(api.MakeCurrent, "OSMesaMakeCurrent");
    get(api.DestroyContext, "OSMesaDestroyContext");
    std::string missing;
    if (ok && !LoadGlFunctions(&api, [lib](const char* s) { return dlsym(lib, s); }, &missing)) {
      ok = false;
      load_error = "OSMesa: libOSMesa " + missing;
    }
    if (!ok) api.CreateContextExt = nullptr;
  });
  if (!api.CreateContextExt) {
    *error = load_error;
    return nullptr;
  }
  return &api;
}

// Colour ramp of the tension scale: blue, cyan, green, yellow, red at 0, 1/4, ..., 1.
constexpr float kRamp[5][3] = {{0.15f, 0.30f, 1.00f},
                               {0.00f, 0.80f, 0.90f},
                               {0.15f, 0.85f, 0.15f},
                               {1.00f, 0.85f, 0.00f},
                               {0.95f, 0.10f, 0.05f}};
constexpr float kSlack[3] = {0.62f, 0.62f, 0.62f};
constexpr float kSand[4] = {0.55f, 0.50f, 0.40f, 1.0f};
constexpr float kArrow[4] = {0.95f, 0.95f, 1.00f, 1.0f};
constexpr float kSurface[4] = {0.55f, 0.75f, 0.90f, 0.35f};  // translucent water surface
constexpr float kFog[4] = {0.06f, 0.18f, 0.30f, 1.0f};       // water colour far from the eye

// Background: water, darker with depth (top to bottom of the image).
constexpr float kWaterTop[3] = {0.16f, 0.36f, 0.52f};
constexpr float kWaterBottom[3] = {0.03f, 0.10f, 0.20f};

std::string BodyName(const mjModel* m, int b) {
  if (b < 0) return "free end";
  const char* name = mj_id2name(m, mjOBJ_BODY, b);
  return name && *name ? name : "body " + std::to_string(b);
}

mjvGeom* NextGeom(mjvScene* scn) {
  if (scn->ngeom >= scn->maxgeom) return nullptr;
  return scn->geoms + scn->ngeom;
}

void FinishDecor(mjvGeom* g, mjvScene* scn) {
  g->category = mjCAT_DECOR;
  g->objtype = mjOBJ_UNKNOWN;
  g->objid = -1;
  g->segid = scn->ngeom;
  ++scn->ngeom;
}

// Radius [m] a tether is drawn with: its own, or thick enough to be seen from the camera's
// distance D [m] (about 1/160 of the view's height).
double DrawnRadius(const Tether& t, double D) {
  return std::max(0.5 * t.params().diameter, D / 250.0);
}

// Radius [m] of the sphere around body b's origin that holds its geoms.
double BodySize(const mjModel* m, int b) {
  double r = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] == b) r = std::max(r, mju_norm3(m->geom_pos + 3 * g) + m->geom_rbound[g]);
  }
  return r;
}

// Half extents [m] of the box that holds geom g in its own frame.
void GeomHalfExtents(const mjModel* m, int g, double e[3]) {
  const double* s = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID:
      e[0] = s[0], e[1] = s[1], e[2] = s[2];
      return;
    case mjGEOM_SPHERE:
      e[0] = e[1] = e[2] = s[0];
      return;
    case mjGEOM_CAPSULE:
      e[0] = e[1] = s[0], e[2] = s[0] + s[1];
      return;
    case mjGEOM_CYLINDER:
      e[0] = e[1] = s[0], e[2] = s[1];
      return;
    default:
      e[0] = e[1] = e[2] = m->geom_rbound[g];
  }
}

// The frame of a free camera: eye [m], forward, up and right unit vectors, as MuJoCo's
// mjv_updateCamera sets them from azimuth a and elevation e: forward (cos e cos a, cos e sin a,
// sin e), up (-sin e cos a, -sin e sin a, cos e), eye = lookat - distance forward.
struct Frame {
  Vec3 eye, f, u, r;
};
Frame MakeFrame(const CameraPose& p) {
  const double a = p.azimuth * kPi / 180, e = p.elevation * kPi / 180;
  Frame fr;
  fr.f = Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
  fr.u = Vec3(-std::sin(e) * std::cos(a), -std::sin(e) * std::sin(a), std::cos(e));
  fr.r = fr.f.cross(fr.u);
  fr.eye = Vec3(p.lookat[0], p.lookat[1], p.lookat[2]) - p.distance * fr.f;
  return fr;
}

// The camera position (in the frame's r, u, f coordinates a, b, c) closest to the points along
// f that projects every point into the normalised window [X0, X1] x [Y0, Y1] (image-plane
// coordinates at unit depth). Each bound is linear in the eye E: (p - E).(r - X1 f) <= 0, etc.;
// so E.n >= max_i p_i.n for four normals n, and the sum of opposite pairs bounds c. Returns c,
// with a and b centred in their feasible intervals.
double FitWindow(const std::vector<Vec3>& p, const Frame& fr, double X0, double X1, double Y0,
                 double Y1, double* a, double* b) {
  double M1 = -mjMAXVAL, M2 = -mjMAXVAL, M3 = -mjMAXVAL, M4 = -mjMAXVAL;
  for (const Vec3& x : p) {
    const double pr = x.dot(fr.r), pu = x.dot(fr.u), pf = x.dot(fr.f);
    M1 = std::max(M1, pr - X1 * pf);
    M2 = std::max(M2, -pr + X0 * pf);
    M3 = std::max(M3, pu - Y1 * pf);
    M4 = std::max(M4, -pu + Y0 * pf);
  }
  const double c = std::min(-(M1 + M2) / (X1 - X0), -(M3 + M4) / (Y1 - Y0));
  *a = 0.5 * ((M1 + X1 * c) + (X0 * c - M2));
  *b = 0.5 * ((M3 + Y1 * c) + (Y0 * c - M4));
  return c;
}

// How far [m] the eye must move back along f so that every point projects into the window
// [X0, X1] x [Y0, Y1] (X0, Y0 < 0 < X1, Y1): 0 if they all do.
double BackOff(const std::vector<Vec3>& p, const Frame& fr, double X0, double X1, double Y0,
               double Y1) {
  double back = 0;
  for (const Vec3& x : p) {
    const Vec3 q = x - fr.eye;
    const double qr = q.dot(fr.r), qu = q.dot(fr.u), qf = q.dot(fr.f);
    // Moving back by s adds s to the depth qf: qr <= X1 (qf + s) etc.
    back = std::max({back, qr / X1 - qf, qr / X0 - qf, qu / Y1 - qf, qu / Y0 - qf});
  }
  return back;
}

// How far [m] the eye must move back along f (which draws every projection toward the frame's
// centre) so that no point projects into one of the blocks (grown by 2 px) that does not hold
// the centre: for a point inside, the fraction lambda of the way to the centre where its ray
// leaves the block gives the needed scale k = 1 - lambda of its offset, qf / (qf + s) = k
// (s capped, see below).
double BackOffBlocks(const std::vector<Vec3>& p, const Frame& fr, const std::vector<Rect>& blocks,
                     int W, int H, double t) {
  const double cx = 0.5 * W, cy = 0.5 * H;
  double back = 0;  // the largest need of a point
  for (const Rect& b : blocks) {
    if (b.empty()) continue;
    const double x0 = b.x - 2, x1 = b.x + b.w + 2, y0 = b.y - 2, y1 = b.y + b.h + 2;
    if (cx >= x0 && cx <= x1 && cy >= y0 && cy <= y1) continue;
    for (const Vec3& x : p) {
      const Vec3 q = x - fr.eye;
      const double qf = q.dot(fr.f);
      if (qf <= 0) continue;
      const double px = cx + q.dot(fr.r) / (qf * t) * 0.5 * H;
      const double py = cy + q.dot(fr.u) / (qf * t) * 0.5 * H;
      if (!(px > x0 && px < x1 && py > y0 && py < y1)) continue;
      double lambda = 1;
      if (cx > px && x1 < cx) lambda = std::min(lambda, (x1 - px) / (cx - px));
      if (cx < px && x0 > cx) lambda = std::min(lambda, (x0 - px) / (cx - px));
      if (cy > py && y1 < cy) lambda = std::min(lambda, (y1 - py) / (cy - py));
      if (cy < py && y0 > cy) lambda = std::min(lambda, (y0 - py) / (cy - py));
      // qf (1 / (1 - lambda) - 1), at most a quarter of the depth: a block reaching near the
      // centre would otherwise ask for a large jump.
      back = std::max(back, qf * std::min(lambda / (1 - lambda), 0.25));
    }
  }
  return back;
}

bool Overlap(const Rect& a, const Rect& b) {
  return !a.empty() && !b.empty() && a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h &&
         b.y < a.y + a.h;
}

// Critically damped filter toward goal g over dt [s] with rate omega [1/s], exact for a
// constant goal: x(t) = g + (x0 - g + (v0 + omega (x0 - g)) t) exp(-omega t).
void Damp(double* x, double* v, double g, double omega, double dt) {
  const double delta = *x - g, e = std::exp(-omega * dt), k = (*v + omega * delta) * dt;
  *x = g + (delta + k) * e;
  *v = (*v - omega * k) * e;
}

// The points the follow and top cameras keep in view: every tether node, and the corners of the
// cube around each free body's geoms.
std::vector<Vec3> ScenePoints(const mjModel* m, const mjData* d, const std::vector<int>& bodies,
                              const std::vector<double>& radius) {
  std::vector<Vec3> pts;
  for (int k = 0; k < TetherCount(m); ++k) {
    const double* x = NodePositions(m, d, k);
    if (!x) continue;
    // The deployed nodes only (with a winch, those before first_node are on the drum).
    for (int i = GetWinch(m, d, k).first_node; i < GetTether(m, k)->nodes(); ++i)
      pts.emplace_back(x + 3 * i);
  }
  for (int b : bodies) {
    const Vec3 c(d->xpos + 3 * b);
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 s(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
      pts.push_back(c + radius[b] * s);
    }
  }
  return pts;
}

constexpr double kFollowElevation = -20;  // [deg] follow camera: looks 20 degrees down
constexpr double kPipFill = 0.85;  // the close-up's vehicle (its sphere) spans 85 % of its height

}  // namespace

std::array<double, 2> ProjectPose(const CameraPose& p, double fovy, int width, int height,
                                  const double x[3]) {
  const Frame fr = MakeFrame(p);
  const Vec3 q = Vec3(x[0], x[1], x[2]) - fr.eye;
  const double t = std::tan(0.5 * fovy * kPi / 180), z = q.dot(fr.f);
  return {0.5 * width + q.dot(fr.r) / (z * t) * 0.5 * height,
          0.5 * height + q.dot(fr.u) / (z * t) * 0.5 * height};
}

double NiceCeil(double x) {
  if (!(x > 0) || !std::isfinite(x)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(x)));
  for (double f : {1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0}) {
    if (f * p >= x * (1 - 1e-12)) return f * p;
  }
  return 10 * p;
}

long long FrameStep(long long k, double fps, double h) {
  return std::llround(static_cast<double>(k) / (fps * h));
}

void TensionColor(double T, double tension_max, float rgba[4]) {
  rgba[3] = 1;
  if (!(T > 0)) {
    std::copy(kSlack, kSlack + 3, rgba);
    return;
  }
  const double s = std::clamp(T / (tension_max > 0 ? tension_max : 1.0), 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(s));
  const float f = static_cast<float>(s - i);
  for (int c = 0; c < 3; ++c) rgba[c] = (1 - f) * kRamp[i][c] + f * kRamp[i + 1][c];
}

bool WritePng(const std::string& path, const unsigned char* rgb, int width, int height,
              std::string* error) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  image.width = width;
  image.height = height;
  image.format = PNG_FORMAT_RGB;
  // A negative row stride starts at the last row: the image is written top-down.
  if (!png_image_write_to_file(&image, path.c_str(), 0, rgb, -3 * width, nullptr)) {
    *error = "cannot write PNG " + path + ": " + image.message;
    return false;
  }
  return true;
}

int Vehicle(const mjModel* m) {
  auto has_free_joint = [m](int b) {
    for (int j = 0; j < m->njnt; ++j) {
      if (m->jnt_bodyid[j] == b && m->jnt_type[j] == mjJNT_FREE) return true;
    }
    return false;
  };
  if (TetherCount(m) > 0) {
    const int b = EndBody(m, 0, 1);
    if (b > 0 && has_free_joint(b)) return b;
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] == mjJNT_FREE) return m->jnt_bodyid[j];
  }
  return -1;
}

std::unique_ptr<Renderer> Renderer::Create(mjModel* m, const RenderOptions& options,
                                           std::string* error) {
  return CreateIn(m, options, nullptr, error);
}

std::unique_ptr<Renderer> Renderer::CreateForWindow(mjModel* m, const RenderOptions& options,
                                                    GlProcLoader load, std::string* error) {
  if (!load) {
    *error = "no GL function loader for the window";
    return nullptr;
  }
  return CreateIn(m, options, load, error);
}

// window: null for an OSMesa context of the renderer's own, else the loader of the window's
// context, current in this thread.
std::unique_ptr<Renderer> Renderer::CreateIn(mjModel* m, const RenderOptions& options,
                                             GlProcLoader window, std::string* error) {
  const RenderOptions& o = options;
  if (o.width < 16 || o.width > 4096 || o.height < 16 || o.height > 4096 || o.width % 2 ||
      o.height % 2) {
    *error = "size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
             " out of range: width and height must be even, in [16, 4096]";
    return nullptr;
  }
  if (o.samples < 0 || o.samples > 16) {
    *error = "samples " + std::to_string(o.samples) + " out of range [0, 16]";
    return nullptr;
  }
  // The command line checks these as it parses them; a library caller (Python) must be told too.
  for (const auto& [name, value] : {std::pair{"tension_max", o.tension_max},
                                    std::pair{"distance", o.distance}}) {
    if (!std::isfinite(value) || value > 1e12) {
      std::ostringstream s;
      s << name << " = " << value << " is not a finite number up to 1e12 (0 or less: automatic)";
      *error = s.str();
      return nullptr;
    }
  }
  std::unique_ptr<Renderer> r(new Renderer());
  r->opt_ = o;
  mjv_defaultCamera(&r->cam_);
  mjv_defaultOption(&r->vopt_);
  mjv_defaultScene(&r->scn_);
  mjr_defaultContext(&r->con_);

  // Vehicle: named, or found.
  if (!o.vehicle.empty()) {
    r->vehicle_ = mj_name2id(m, mjOBJ_BODY, o.vehicle.c_str());
    if (r->vehicle_ < 0) {
      *error = "no body named '" + o.vehicle + "' in the model";
      return nullptr;
    }
  } else {
    r->vehicle_ = Vehicle(m);
  }

  // Bodies framed with the tethers: those with a free joint, and the bodies (not the world)
  // that hold a tether's end with geoms of their own: a TMS or a boat, which would otherwise be
  // cut at the frame's edge when the tether leaves it from below.
  r->body_radius_.resize(m->nbody);
  for (int b = 0; b < m->nbody; ++b) r->body_radius_[b] = BodySize(m, b);
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] == mjJNT_FREE) r->free_bodies_.push_back(m->jnt_bodyid[j]);
  }
  for (int k = 0; k < TetherCount(m); ++k) {
    for (int end = 0; end < 2; ++end) {
      const int b = EndBody(m, k, end);
      if (b > 0 && r->body_radius_[b] > 0 &&
          std::find(r->free_bodies_.begin(), r->free_bodies_.end(), b) == r->free_bodies_.end()) {
        r->free_bodies_.push_back(b);
      }
    }
  }

  // Fixed follow distance (--distance, and the fallback): the longest tether in view.
  double L = 0;
  for (int k = 0; k < TetherCount(m); ++k) L = std::max(L, GetTether(m, k)->params().length);
  r->follow_distance_ = o.distance > 0 ? o.distance
                        : L > 0        ? 1.25 * L
                                       : std::max(3.0, 2.0 * m->stat.extent);
  if (TetherCount(m) > 0) {
    // Across the current: the uniform one, or a profile's fastest row.
    const Water& w = GetTether(m, 0)->env().water;
    Vec3 u = w.current;
    for (const Vec3& row : w.profile.u) {
      if (row.norm() > u.norm()) u = row;
    }
    if (std::hypot(u.x(), u.y()) > 0) {
      r->follow_azimuth_ = std::atan2(u.y(), u.x()) * 180 / kPi + 90;
    }
  }

  // Camera.
  const std::string& c = o.camera;
  r->cam_.type = mjCAMERA_FREE;  // follow and track: placed from the state at each frame
  if (c.rfind("track:", 0) == 0) {
    const std::string body = c.substr(6);
    const int b = mj_name2id(m, mjOBJ_BODY, body.c_str());
    if (b < 0) {
      *error = "--camera " + c + ": no body named '" + body + "' in the model";
      return nullptr;
    }
    r->track_body_ = b;
    // 8 radii: the sphere holding its geoms spans about 30 % of the frame's height (45 degree
    // field of view), so a vehicle stays well above the 40 px of the close-up threshold at 360 rows.
    if (o.distance <= 0) r->follow_distance_ = std::max(1.0, 8 * BodySize(m, b));
    if (o.vehicle.empty()) r->vehicle_ = b;
  } else if (c == "top") {
    r->top_ = true;
  } else if (c != "follow") {
    const int id = mj_name2id(m, mjOBJ_CAMERA, c.c_str());
    if (id < 0) {
      *error = "--camera " + c +
               ": not 'follow', 'top', 'track:BODY' or the name of a <camera> in the model";
      return nullptr;
    }
    r->cam_.type = mjCAMERA_FIXED;
    r->cam_.fixedcamid = id;
  }
  r->cam_.distance = r->follow_distance_;
  r->cam_.azimuth = r->follow_azimuth_;
  r->cam_.elevation = r->top_ ? -90 : kFollowElevation;

  // Water: fog; a surface when a tether end starts within 1 m of z = 0.
  if (TetherCount(m) > 0 && GetTether(m, 0)->env().wet) {
    r->wet_ = true;
    mjData* d0 = mj_makeData(m);
    mj_forward(m, d0);
    for (int k = 0; k < TetherCount(m); ++k) {
      const double* x = NodePositions(m, d0, k);
      const int n = GetTether(m, k)->nodes();
      if (x && (std::abs(x[2]) < 1 || std::abs(x[3 * (n - 1) + 2]) < 1)) r->has_surface_ = true;
    }
    mj_deleteData(d0);
  }

  // A model plane at the seabed height stands for the seabed; otherwise one is drawn.
  if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.has_seabed) {
    const double zb = GetTether(m, 0)->env().water.seabed;
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_type[g] == mjGEOM_PLANE && m->geom_bodyid[g] == 0 &&
          std::abs(m->geom_pos[3 * g + 2] - zb) < 1e-6) {
        r->seabed_geom_ = g;
      }
    }
  }

  r->options_cam_ = r->cam_;
  if (window) {
    // The window's context, current in this thread: its own GL functions.
    r->window_ = true;
    r->window_gl_ = std::make_unique<OsMesaApi>();
    std::string missing;
    if (!LoadGlFunctions(
            r->window_gl_.get(), [window](const char* s) { return window(s); }, &missing)) {
      *error = "OpenGL: the window's context " + missing;
      return nullptr;
    }
    r->gl_ = r->window_gl_.get();
  } else {
    // OSMesa context with its own (unused) default framebuffer; MuJoCo draws off-screen.
    const OsMesaApi* gl = OsMesa(error);
    if (!gl) return nullptr;
    r->gl_ = gl;
    OSMesaContext ctx = gl->CreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
    if (!ctx) {
      *error = "OSMesa: cannot create a context (OSMesaCreateContextExt)";
      return nullptr;
    }
    r->osmesa_ = ctx;
    r->osmesa_buffer_.reset(new unsigned char[4 * o.width * o.height]);
    if (!gl->MakeCurrent(ctx, r->osmesa_buffer_.get(), GL_UNSIGNED_BYTE, o.width, o.height)) {
      *error = "OSMesa: cannot make the context current (OSMesaMakeCurrent)";
      return nullptr;
    }
  }

  // The off-screen buffer is sized from the model: set it to the requested size, since a larger
  // viewport would be cropped silently.
  m->vis.global.offwidth = o.width;
  m->vis.global.offheight = o.height;
  m->vis.quality.offsamples = o.samples;
  // The far clipping plane (a multiple of the model's extent, which ignores the tethers) beyond
  // the farthest the follow camera goes: a few tether lengths.
  if (m->stat.extent > 0) {
    m->vis.map.zfar = std::max<float>(m->vis.map.zfar, (10 * L + 100) / m->stat.extent);
  }

  int tether_geoms = 0;
  for (int k = 0; k < TetherCount(m); ++k) tether_geoms += GetTether(m, k)->segments();
  mjv_makeScene(m, &r->scn_, 2000 + m->ngeom + tether_geoms);
  r->scene_made_ = true;
  // Light the scene from the camera enough that a deep seabed is not black.
  m->vis.headlight.ambient[0] = m->vis.headlight.ambient[1] = m->vis.headlight.ambient[2] =
      std::max(m->vis.headlight.ambient[0], 0.25f);
  m->vis.headlight.diffuse[0] = m->vis.headlight.diffuse[1] = m->vis.headlight.diffuse[2] =
      std::max(m->vis.headlight.diffuse[0], 0.6f);
  // Font: 150 % at 720 rows, in proportion to the height (MuJoCo has 50 % steps), smaller
  // while the HUD or the colour scale would take too much of the frame.
  int fontscale = std::clamp(50 * static_cast<int>(std::lround(3.0 * o.height / 720)), 50, 300);
  for (;; fontscale -= 50) {
    mjr_makeContext(m, &r->con_, fontscale);
    r->context_made_ = true;
    r->ComputeLayout(m);
    const Layout& l = r->layout_;
    const bool fits = l.hud.w <= 0.45 * o.width && l.hud.h <= 0.4 * o.height &&
                      l.scale.w <= 0.7 * o.width && l.scale.h <= 0.25 * o.height;
    if (fits || fontscale <= 50) break;
    mjr_freeContext(&r->con_);
    mjr_defaultContext(&r->con_);
    r->context_made_ = false;
  }
  if (window) {
    mjr_setBuffer(mjFB_WINDOW, &r->con_);
    return r;
  }
  mjr_setBuffer(mjFB_OFFSCREEN, &r->con_);
  if (r->con_.currentBuffer != mjFB_OFFSCREEN) {
    *error = "MuJoCo: the off-screen framebuffer is not available";
    return nullptr;
  }
  if (r->con_.offWidth != o.width || r->con_.offHeight != o.height) {
    *error = "MuJoCo: off-screen buffer is " + std::to_string(r->con_.offWidth) + "x" +
             std::to_string(r->con_.offHeight) + ", not the requested " + std::to_string(o.width) +
             "x" + std::to_string(o.height);
    return nullptr;
  }
  return r;
}

Renderer::~Renderer() {
  if (osmesa_) {  // (a window's context is current already)
    gl_->MakeCurrent(static_cast<OSMesaContext>(osmesa_), osmesa_buffer_.get(), GL_UNSIGNED_BYTE,
                     opt_.width, opt_.height);
  }
  if (context_made_) mjr_freeContext(&con_);
  if (scene_made_) mjv_freeScene(&scn_);
  if (osmesa_) gl_->DestroyContext(static_cast<OSMesaContext>(osmesa_));
}

int Renderer::TextWidth(const std::string& text) const {
  int w = 0;
  for (unsigned char c : text) w += c < 127 ? con_.charWidth[c] : 0;
  return w;
}

Layout Renderer::layout() const {
  Layout l = layout_;
  if (!pip_shown_) l.pip = Rect();
  return l;
}

// The HUD's lines (title, and the widest value it can show), one per quantity.
// Compact (narrow frames): shorter titles.
static std::vector<std::string> HudTitles(const mjModel* m, int vehicle, bool compact) {
  std::vector<std::string> t = {"time"};
  const int n = TetherCount(m);
  for (int k = 0; k < n; ++k) {
    const std::string prefix = n > 1 ? TetherName(m, k) + ": " : "";
    for (int end = 0; end < 2; ++end) {
      t.push_back(prefix + (compact ? "T " : "T at ") + BodyName(m, EndBody(m, k, end)));
    }
    if (GetTether(m, k)->params().winch) t.push_back(prefix + (compact ? "out" : "deployed"));
  }
  if (vehicle >= 0) {
    t.push_back(compact ? "depth" : "depth of " + BodyName(m, vehicle));
    if (n > 0 && GetTether(m, 0)->env().water.has_seabed) t.push_back("altitude");
  }
  if (n > 0 && GetTether(m, 0)->env().water.has_current()) t.push_back("current");
  return t;
}

// Rectangles of the overlays, from the font's metrics and the frame size.
void Renderer::ComputeLayout(const mjModel* m) {
  const int W = opt_.width, H = opt_.height, ch = con_.charHeight;
  const int pad = std::max(2, ch / 4);
  Layout l;
  if (opt_.hud) {
    int tw = 0;
    const std::vector<std::string> titles = HudTitles(m, vehicle_, W < 480);
    for (const std::string& t : titles) tw = std::max(tw, TextWidth(t));
    const int vw = std::max(TextWidth("-0000.0 N"), TextWidth("000.00 m/s"));
    l.hud = {0, 0, pad + tw + ch / 2 + vw + pad, static_cast<int>(titles.size()) * ch + 2 * pad};
    l.hud.y = H - l.hud.h;
    if (TetherCount(m) > 0) {
      // Colour scale, from the bottom: tick labels, bar, title; the slack swatch on the left.
      int tick = 0;
      const double tmax = opt_.tension_max > 0 ? opt_.tension_max : 1;
      char buf[64];
      for (int i = 0; i <= 4; ++i) {
        std::snprintf(buf, sizeof(buf), "%g", tmax * i / 4);
        tick = std::max(tick, TextWidth(buf));
      }
      const int title = TextWidth("segment tension [N]");
      const int bar_w = std::max({W / 4, title, 4 * (tick + ch / 2)});
      const int bar_h = std::max(4, ch / 2);
      const int slack = std::max(TextWidth("slack"), ch);
      const int right = W - pad - tick / 2;  // bar's right end: the last tick label fits
      const int left = right - bar_w;
      l.scale.x = left - ch / 2 - slack - pad;
      l.scale.w = W - l.scale.x;
      l.scale.h = pad + ch + pad / 2 + bar_h + pad / 2 + ch + pad;
      l.label = {left + (bar_w - title) / 2, l.scale.h - pad - ch, title, ch};
    }
  }
  if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.has_current()) {
    const int w = std::max(W / 7, 4 * ch), h = std::max(H / 7, 3 * ch);
    l.arrow = {W - w, H - h, w, h};
  }
  if (vehicle_ >= 0 && opt_.pip_min_px > 0) {
    int h = std::max(H * 3 / 10, 96), w = h * 4 / 3;
    if (w > 2 * W / 5) w = 2 * W / 5, h = w * 3 / 4;
    // Bottom left, so beside the colour scale (bottom right) and below the HUD (top left): in a
    // small frame the scale's panel reaches into the left half (at 320x240 its left edge is at
    // x = 106, where a 96 px high close-up would end at 130), so the close-up shrinks to fit.
    const int w_max = l.scale.empty() ? W - 2 * pad : l.scale.x - 2 * pad;
    const int h_max = l.hud.empty() ? H - 2 * pad : l.hud.y - 2 * pad;
    if (w > w_max) w = w_max, h = w * 3 / 4;
    if (h > h_max) h = h_max, w = h * 4 / 3;
    // Smaller than three lines of text it shows nothing worth a corner: no close-up.
    if (h >= 3 * ch) l.pip = {pad, pad, w, h};
  }
  layout_ = l;
  layout_dirty_ = false;
}

// Projected size [pixel] of body b's drawn geoms through pose p: the larger side of the box
// bounding the projections of their boxes' corners.
double Renderer::VehiclePixels(const mjModel* m, const mjData* d, const CameraPose& p) const {
  double lo[2] = {mjMAXVAL, mjMAXVAL}, hi[2] = {-mjMAXVAL, -mjMAXVAL};
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] != vehicle_) continue;
    const int group = std::clamp(m->geom_group[g], 0, mjNGROUP - 1);
    if (!vopt_.geomgroup[group] || m->geom_rgba[4 * g + 3] == 0) continue;
    double e[3];
    GeomHalfExtents(m, g, e);
    for (int corner = 0; corner < 8; ++corner) {
      double local[3], world[3];
      for (int i = 0; i < 3; ++i) local[i] = (corner >> i & 1 ? 1 : -1) * e[i];
      mju_rotVecMat(world, local, d->geom_xmat + 9 * g);
      mju_addTo3(world, d->geom_xpos + 3 * g);
      const std::array<double, 2> px =
          ProjectPose(p, m->vis.global.fovy, opt_.width, opt_.height, world);
      for (int i = 0; i < 2; ++i) lo[i] = std::min(lo[i], px[i]), hi[i] = std::max(hi[i], px[i]);
    }
  }
  return lo[0] <= hi[0] ? std::max(hi[0] - lo[0], hi[1] - lo[1]) : 0;
}

CameraPose Renderer::PipPose(const mjModel* m, const mjData* d, const CameraPose& main) const {
  CameraPose p = main;
  const double t = std::tan(0.5 * m->vis.global.fovy * kPi / 180);
  const double radius = std::max(body_radius_[vehicle_], 1e-3);
  for (int i = 0; i < 3; ++i) p.lookat[i] = d->xpos[3 * vehicle_ + i];
  p.distance = radius / (kPipFill * t);
  p.pip = false;
  return p;
}

// The framing the follow and top cameras move toward: the closest camera, in their direction,
// that projects every tether node and every free body (the cube around its geoms) into the
// largest free part of the frame (outside the overlays' rectangles, with a margin).
CameraPose Renderer::Target(const mjModel* m, const mjData* d, bool pip) const {
  CameraPose p;
  p.azimuth = follow_azimuth_;
  p.elevation = top_ ? -90 : kFollowElevation;
  p.distance = follow_distance_;
  std::vector<Vec3> pts = ScenePoints(m, d, free_bodies_, body_radius_);
  double Dmin = 1;  // [m] closest the camera gets to the middle of the scene
  for (int b : free_bodies_) Dmin = std::max(Dmin, 4 * body_radius_[b]);
  if (pts.empty()) pts.emplace_back(m->stat.center[0], m->stat.center[1], m->stat.center[2]);
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& x : pts) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  if (opt_.distance > 0) {  // fixed distance: look at the middle of the box bounding them
    for (int i = 0; i < 3; ++i) p.lookat[i] = 0.5 * (lo[i] + hi[i]);
    return p;
  }

  // Free rectangles: every one whose sides lie on the frame's or the overlays' edges and that
  // covers no overlay; the one that lets the camera come closest wins.
  const int W = opt_.width, H = opt_.height;
  std::vector<Rect> blocks = {layout_.hud, layout_.scale, layout_.arrow};
  if (pip) blocks.push_back(layout_.pip);
  std::vector<int> xs = {0, W}, ys = {0, H};
  for (const Rect& b : blocks) {
    if (b.empty()) continue;
    xs.insert(xs.end(), {b.x, b.x + b.w});
    ys.insert(ys.end(), {b.y, b.y + b.h});
  }
  const double t = std::tan(0.5 * m->vis.global.fovy * kPi / 180);
  const double margin = std::max(4.0, 0.03 * std::min(W, H));  // [pixel]
  auto nx = [&](double px) { return (px - 0.5 * W) / (0.5 * H) * t; };
  auto ny = [&](double py) { return (py - 0.5 * H) / (0.5 * H) * t; };
  const Frame fr = MakeFrame(p);
  double best_c = -mjMAXVAL, best_a = 0, best_b = 0;
  for (int x0 : xs) {
    for (int x1 : xs) {
      if (x1 - x0 < W / 3) continue;
      for (int y0 : ys) {
        for (int y1 : ys) {
          if (y1 - y0 < H / 3) continue;
          const Rect r = {x0, y0, x1 - x0, y1 - y0};
          bool free = true;
          for (const Rect& b : blocks) free = free && !Overlap(r, b);
          if (!free) continue;
          double a, b;
          const double c = FitWindow(pts, fr, nx(x0 + margin), nx(x1 - margin), ny(y0 + margin),
                                     ny(y1 - margin), &a, &b);
          if (c > best_c) best_c = c, best_a = a, best_b = b;
        }
      }
    }
  }
  if (best_c == -mjMAXVAL) {  // no free rectangle that large: the whole frame
    best_c = FitWindow(pts, fr, nx(margin), nx(W - margin), ny(margin), ny(H - margin), &best_a,
                       &best_b);
  }
  // Distance: to the middle of the points' depths, at least Dmin.
  double fmin = mjMAXVAL, fmax = -mjMAXVAL;
  for (const Vec3& x : pts) fmin = std::min(fmin, x.dot(fr.f)), fmax = std::max(fmax, x.dot(fr.f));
  const double mid = 0.5 * (fmin + fmax);
  double c = best_c;
  if (mid - c < Dmin) c = mid - Dmin;
  const Vec3 eye = best_a * fr.r + best_b * fr.u + c * fr.f;
  p.distance = mid - c;
  const Vec3 look = eye + p.distance * fr.f;
  for (int i = 0; i < 3; ++i) p.lookat[i] = look[i];
  return p;
}

CameraPose Renderer::NextPose(const mjModel* m, const mjData* d) {
  if (layout_dirty_) ComputeLayout(m);  // (a window resized)
  CameraPose p;
  p.azimuth = follow_azimuth_;
  p.elevation = top_ ? -90 : kFollowElevation;
  p.distance = follow_distance_;
  if (cam_.type != mjCAMERA_FREE) return p;
  if (track_body_ >= 0) {
    for (int i = 0; i < 3; ++i) p.lookat[i] = d->xpos[3 * track_body_ + i];
    return p;
  }
  // Filter the look-at point and log(distance) toward the target (the first frame, a frame
  // back in time and no smoothing jump to it).
  CameraPose target = Target(m, d, pip_shown_);
  if (!filter_started_ && vehicle_ >= 0 && opt_.pip_min_px > 0 &&
      VehiclePixels(m, d, target) < opt_.pip_min_px) {
    pip_shown_ = true;  // the first frame is framed with the close-up it will show
    target = Target(m, d, true);
  }
  const double goal[4] = {target.lookat[0], target.lookat[1], target.lookat[2],
                          std::log(target.distance)};
  const double dt = d->time - filter_time_;
  if (!filter_started_ || !(dt >= 0) || !(opt_.smoothing > 0)) {
    for (int i = 0; i < 4; ++i) state_[i] = goal[i], rate_[i] = 0;
    filter_started_ = true;
  } else {
    for (int i = 0; i < 4; ++i) Damp(&state_[i], &rate_[i], goal[i], 1 / opt_.smoothing, dt);
  }
  filter_time_ = d->time;
  for (int i = 0; i < 3; ++i) p.lookat[i] = state_[i];
  p.distance = std::exp(state_[3]);

  // The filter lags: back off along the view if a node or a vehicle would leave the frame.
  if (opt_.distance <= 0) {
    const std::vector<Vec3> pts = ScenePoints(m, d, free_bodies_, body_radius_);
    const double t = std::tan(0.5 * m->vis.global.fovy * kPi / 180);
    const double X = 0.97 * t * opt_.width / opt_.height, Y = 0.97 * t;
    double back = BackOff(pts, MakeFrame(p), -X, X, -Y, Y);
    // Then out of the overlays (a few rounds: a point drawn toward the centre may enter another).
    // (Not out of the close-up: it appears at once, the filter moves the scene away from it.)
    const std::vector<Rect> blocks = {layout_.hud, layout_.scale, layout_.arrow};
    for (int round = 0; round < 3; ++round) {
      CameraPose q = p;
      q.distance += back;
      const double more = BackOffBlocks(pts, MakeFrame(q), blocks, opt_.width, opt_.height, t);
      if (!(more > 0)) break;
      back += more;
    }
    if (back > 0) {
      p.distance += back;
      state_[3] = std::log(p.distance);
      rate_[3] = std::max(rate_[3], 0.0);
    }
  }

  // Close-up: on below pip_min_px, off above 1.2 x (no flicker at the threshold).
  if (vehicle_ >= 0 && opt_.pip_min_px > 0) {
    const double size = VehiclePixels(m, d, p);
    if (size < opt_.pip_min_px) pip_shown_ = true;
    if (size > 1.2 * opt_.pip_min_px) pip_shown_ = false;
  }
  p.pip = pip_shown_;
  return p;
}

// Tethers, seabed and (overlays: in the main view) the current arrow, added to the scene as
// decor geoms; D [m] is the camera's distance (tether thickness, seabed size).
void Renderer::Decorate(const mjModel* m, const mjData* d, double D, bool overlays) {
  std::vector<double> T;
  const mjvGLCamera gl = mjv_averageCamera(&scn_.camera[0], &scn_.camera[1]);
  // Camera frame and a reference point in front of it at distance D.
  const Vec3 eye(gl.pos[0], gl.pos[1], gl.pos[2]);
  const Vec3 fwd(gl.forward[0], gl.forward[1], gl.forward[2]);
  const Vec3 up(gl.up[0], gl.up[1], gl.up[2]);
  const Vec3 right = fwd.cross(up);
  const Vec3 ref = eye + D * fwd;
  const double t = 0.5 * (gl.frustum_top - gl.frustum_bottom) / gl.frustum_near;
  if (opt_.draw_tethers) {
    for (int k = 0; k < TetherCount(m); ++k) {
      const Tether& tether = *GetTether(m, k);
      const double* x = NodePositions(m, d, k);
      if (!x) continue;
      T.resize(tether.segments());
      GetTensions(m, d, k, T.data());
      const double radius = DrawnRadius(tether, D);
      for (int j = GetWinch(m, d, k).first_node; j < tether.segments(); ++j) {  // deployed only
        const double* a = x + 3 * j;
        const double* b = x + 3 * j + 3;
        if (mju_dist3(a, b) < 1e-9) continue;
        mjvGeom* g = NextGeom(&scn_);
        if (!g) return;
        float rgba[4];
        TensionColor(T[j], opt_.tension_max, rgba);
        mjv_initGeom(g, mjGEOM_CAPSULE, nullptr, nullptr, nullptr, rgba);
        mjv_makeConnector(g, mjGEOM_CAPSULE, T[j] > 0 ? radius : 0.5 * radius, a[0], a[1], a[2],
                          b[0], b[1], b[2]);
        g->specular = 0.3f;
        FinishDecor(g, &scn_);
      }
    }
  }

  if (TetherCount(m) == 0) return;
  const Water& w = GetTether(m, 0)->env().water;

  // Seabed: a slab whose top is at the seabed height, under the camera's reference point
  // (a seabed=GEOMNAME seabed is that geom, which MuJoCo draws).
  if (w.has_seabed && seabed_geom_ < 0 && !w.surface.declared()) {
    if (mjvGeom* g = NextGeom(&scn_)) {
      const double thick = 0.01 * D;
      const mjtNum size[3] = {4 * D, 4 * D, thick};
      const mjtNum pos[3] = {ref.x(), ref.y(), w.seabed - thick};
      const mjtNum mat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      mjv_initGeom(g, mjGEOM_BOX, size, pos, mat, kSand);
      FinishDecor(g, &scn_);
    }
  }

  // Water surface: a translucent sheet at z = 0 under the reference point, when the scene has
  // one (a tether end within 1 m of z = 0 at the start).
  if (has_surface_) {
    if (mjvGeom* g = NextGeom(&scn_)) {
      const mjtNum size[3] = {4 * D, 4 * D, 1e-3 * D};
      const mjtNum pos[3] = {ref.x(), ref.y(), 0};
      const mjtNum mat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      mjv_initGeom(g, mjGEOM_BOX, size, pos, mat, kSurface);
      FinishDecor(g, &scn_);
    }
  }

  // Current: an arrow in the top-right rectangle, 0.5 D per m/s, at most 70 % of its width.
  // With a current profile, the current at the depth of the view's centre (the reference
  // point), which the HUD shows too.
  const Vec3 current = w.CurrentAt(ref.z());
  const double speed = current.norm();
  if (overlays) current_shown_ = speed;
  const Rect& box = layout_.arrow;
  if (overlays && speed > 0 && !box.empty()) {
    if (mjvGeom* g = NextGeom(&scn_)) {
      const double W = opt_.width, H = opt_.height;
      const double per_px = 2 * D * t / H;  // [m] per pixel at depth D
      const Vec3 dir = current / speed;
      const double len = std::min(0.5 * D * speed, 0.7 * box.w * per_px);
      const double cx = box.x + 0.5 * box.w - 0.5 * W, cy = box.y + 0.5 * box.h - 0.5 * H;
      const Vec3 c = ref + cx * per_px * right + cy * per_px * up;
      const Vec3 a = c - 0.5 * len * dir, b = c + 0.5 * len * dir;
      mjv_initGeom(g, mjGEOM_ARROW, nullptr, nullptr, nullptr, kArrow);
      mjv_makeConnector(g, mjGEOM_ARROW, 0.04 * std::min(box.w, box.h) * per_px, a.x(), a.y(),
                        a.z(), b.x(), b.y(), b.z());
      FinishDecor(g, &scn_);
    }
  }
}

// Text left-aligned at (x, y) [pixel]: mjr_label centres its text in the rectangle, which is
// as wide as the text.
void Renderer::Text(int x, int y, const std::string& text, float gray) {
  mjr_label({x, y, TextWidth(text), con_.charHeight}, mjFONT_NORMAL, text.c_str(), 0, 0, 0, 0, gray,
            gray, gray, &con_);
}

void Renderer::DrawHud(const mjModel* m, const mjData* d) {
  const int ch = con_.charHeight, pad = std::max(2, ch / 4);
  char buf[128];
  // Top left: one line per quantity, the title left and its value right-aligned.
  const std::vector<std::string> titles = HudTitles(m, vehicle_, opt_.width < 480);
  std::vector<std::string> values;
  std::snprintf(buf, sizeof(buf), "%.2f s", d->time);
  values.push_back(buf);
  for (int k = 0; k < TetherCount(m); ++k) {
    const EndReactions r = GetReactions(m, d, k);
    for (double T : {r.tension_a, r.tension_b}) {
      std::snprintf(buf, sizeof(buf), "%.1f N", T);
      values.push_back(buf);
    }
    const WinchState w = GetWinch(m, d, k);
    if (w.present) {  // its title: HudTitles
      std::snprintf(buf, sizeof(buf), "%.2f m", w.length);
      values.push_back(buf);
    }
  }
  if (vehicle_ >= 0) {
    std::snprintf(buf, sizeof(buf), "%.2f m", -d->xpos[3 * vehicle_ + 2]);
    values.push_back(buf);
    if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.has_seabed) {
      std::snprintf(buf, sizeof(buf), "%.2f m",
                    d->xpos[3 * vehicle_ + 2] - GetTether(m, 0)->env().water.seabed);
      values.push_back(buf);
    }
  }
  if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.has_current()) {
    std::snprintf(buf, sizeof(buf), "%.2f m/s", current_shown_);  // as the arrow (Decorate)
    values.push_back(buf);
  }
  const Rect& hud = layout_.hud;
  mjr_rectangle({hud.x, hud.y, hud.w, hud.h}, 0.0f, 0.0f, 0.0f, 0.55f);
  for (size_t i = 0; i < titles.size() && i < values.size(); ++i) {
    const int y = hud.y + hud.h - pad - static_cast<int>(i + 1) * ch;
    Text(hud.x + pad, y, titles[i], 0.85f);
    // A value wider than the room reserved (unlikely: 13 characters) is clipped at the panel.
    Text(std::max(hud.x + hud.w - pad - TextWidth(values[i]), hud.x + pad), y, values[i], 1);
  }

  if (TetherCount(m) == 0) return;
  // Bottom right: a ramp over [0, tension_max], tick labels, its title, and a slack swatch.
  const Rect& sc = layout_.scale;
  const Rect& title = layout_.label;
  mjr_rectangle({sc.x, sc.y, sc.w, sc.h}, 0.0f, 0.0f, 0.0f, 0.55f);
  int tick = 0;
  const double tmax = opt_.tension_max > 0 ? opt_.tension_max : 1;
  for (int i = 0; i <= 4; ++i) {
    std::snprintf(buf, sizeof(buf), "%g", tmax * i / 4);
    tick = std::max(tick, TextWidth(buf));
  }
  const int right = opt_.width - pad - tick / 2;
  const int bar_w = std::max({opt_.width / 4, title.w, 4 * (tick + ch / 2)});
  const int left = right - bar_w;
  const int bar_h = std::max(4, ch / 2);
  const int bar_y = sc.y + pad + ch + pad / 2;
  const int nstrip = 64;
  for (int i = 0; i < nstrip; ++i) {
    float rgba[4];
    TensionColor((i + 0.5) / nstrip * opt_.tension_max, opt_.tension_max, rgba);
    const int x0 = left + i * bar_w / nstrip, x1 = left + (i + 1) * bar_w / nstrip;
    mjr_rectangle({x0, bar_y, x1 - x0, bar_h}, rgba[0], rgba[1], rgba[2], 1);
  }
  for (int i = 0; i <= 4; ++i) {
    std::snprintf(buf, sizeof(buf), "%g", tmax * i / 4);
    Text(left + i * bar_w / 4 - TextWidth(buf) / 2, sc.y + pad, buf, 1);
  }
  Text(title.x, title.y, "segment tension [N]", 1);
  const int slack = std::max(TextWidth("slack"), ch);
  const int sx = left - ch / 2 - slack;  // left edge of the slack column
  mjr_rectangle({sx + (slack - ch) / 2, bar_y, ch, bar_h}, kSlack[0], kSlack[1], kSlack[2], 1);
  Text(sx + (slack - TextWidth("slack")) / 2, sc.y + pad, "slack", 1);
}

// Water behind the scene in rectangle r: a vertical gradient drawn at the far plane, where the
// depth test lets it through only on pixels that nothing else covered.
void Renderer::DrawWater(const Rect& r) {
  gl_->PushAttrib(GL_ALL_ATTRIB_BITS);
  gl_->Disable(GL_LIGHTING);
  gl_->Disable(GL_TEXTURE_2D);
  gl_->Disable(GL_BLEND);
  gl_->Disable(GL_CULL_FACE);
  gl_->Disable(GL_FOG);
  gl_->Enable(GL_DEPTH_TEST);
  gl_->DepthFunc(GL_LEQUAL);
  gl_->DepthMask(GL_FALSE);
  gl_->Viewport(r.x, r.y, r.w, r.h);
  gl_->MatrixMode(GL_PROJECTION);
  gl_->PushMatrix();
  gl_->LoadIdentity();
  gl_->MatrixMode(GL_MODELVIEW);
  gl_->PushMatrix();
  gl_->LoadIdentity();
  gl_->ShadeModel(GL_SMOOTH);
  gl_->Begin(GL_QUADS);
  gl_->Color3fv(kWaterBottom);
  gl_->Vertex3f(-1, -1, 1);
  gl_->Vertex3f(1, -1, 1);
  gl_->Color3fv(kWaterTop);
  gl_->Vertex3f(1, 1, 1);
  gl_->Vertex3f(-1, 1, 1);
  gl_->End();
  gl_->PopMatrix();
  gl_->MatrixMode(GL_PROJECTION);
  gl_->PopMatrix();
  gl_->MatrixMode(GL_MODELVIEW);
  gl_->PopAttrib();
}

// Depth cue in water: linear fog toward the water's colour, from 0.7 D to 4 D from the eye (D
// the camera's distance to what it looks at).
void Renderer::Fog(double D) {
  scn_.flags[mjRND_FOG] = wet_;
  con_.fogStart = static_cast<float>(0.7 * D);
  con_.fogEnd = static_cast<float>(4 * D);
  std::copy(kFog, kFog + 4, con_.fogRGBA);
}

// Makes the renderer's context current (OSMesa) and selects the buffer MuJoCo draws into.
void Renderer::BeginFrame() {
  if (window_) {
    mjr_setBuffer(mjFB_WINDOW, &con_);
    return;
  }
  gl_->MakeCurrent(static_cast<OSMesaContext>(osmesa_), osmesa_buffer_.get(), GL_UNSIGNED_BYTE,
                   opt_.width, opt_.height);
  mjr_setBuffer(mjFB_OFFSCREEN, &con_);
}

void Renderer::Render(const mjModel* m, mjData* d, unsigned char* rgb, float* depth) {
  // A camera the caller moves has no filter to advance.
  RenderAt(m, d, free_camera_ ? CameraPose() : NextPose(m, d), rgb, depth);
}

void Renderer::RenderAt(const mjModel* m, mjData* d, const CameraPose& pose, unsigned char* rgb,
                        float* depth) {
  BeginFrame();
  if (layout_dirty_) ComputeLayout(m);
  // The pose places the follow, top and track cameras; a model's camera and a camera the caller
  // moves (the viewer's mouse) ignore it.
  const bool posed = cam_.type == mjCAMERA_FREE && !free_camera_;
  if (posed) {
    for (int i = 0; i < 3; ++i) cam_.lookat[i] = pose.lookat[i];
    cam_.distance = pose.distance;
    cam_.azimuth = pose.azimuth;
    cam_.elevation = pose.elevation;
  }
  const double D = cam_.type == mjCAMERA_FREE ? cam_.distance : follow_distance_;
  mjv_updateScene(m, d, &vopt_, nullptr, &cam_, mjCAT_ALL, &scn_);
  Decorate(m, d, D, true);
  if (opt_.overlay) DrawOverlay(m, d, D);
  Fog(D);
  const Rect all = {0, 0, opt_.width, opt_.height};
  mjr_render({0, 0, opt_.width, opt_.height}, &scn_, &con_);
  DrawWater(all);
  if (opt_.overlay) DrawOverlayLabels(m, d);

  // Close-up of the vehicle, bottom left, framed by a thin light border.
  pip_rendered_ = false;
  if (posed && pose.pip && vehicle_ >= 0 && !layout_.pip.empty()) {
    const mjvGLCamera main[2] = {scn_.camera[0], scn_.camera[1]};
    const CameraPose pp = PipPose(m, d, pose);
    mjvCamera cam = cam_;
    for (int i = 0; i < 3; ++i) cam.lookat[i] = pp.lookat[i];
    cam.distance = pp.distance;
    mjv_updateScene(m, d, &vopt_, nullptr, &cam, mjCAT_ALL, &scn_);
    Decorate(m, d, pp.distance, false);
    Fog(pp.distance);
    const Rect& r = layout_.pip;
    const int b = std::max(1, opt_.height / 240);
    mjr_rectangle({r.x - b, r.y - b, r.w + 2 * b, r.h + 2 * b}, 0.9f, 0.9f, 0.9f, 1);
    mjr_render({r.x, r.y, r.w, r.h}, &scn_, &con_);
    DrawWater(r);
    pip_camera_[0] = mjv_averageCamera(&scn_.camera[0], &scn_.camera[1]);
    pip_rendered_ = true;
    scn_.camera[0] = main[0];
    scn_.camera[1] = main[1];
  }
  if (opt_.hud) DrawHud(m, d);

  if (rgb || depth) mjr_readPixels(rgb, depth, {0, 0, opt_.width, opt_.height}, &con_);
}

void Renderer::Caption(const std::string& left, const std::string& right) {
  const mjrRect view = {0, 0, opt_.width, opt_.height};
  mjr_overlay(mjFONT_NORMAL, mjGRID_BOTTOMLEFT, view, left.c_str(), right.c_str(), &con_);
}

void Renderer::ReadPixels(unsigned char* rgb, float* depth) {
  const mjrRect view = {0, 0, opt_.width, opt_.height};
  mjr_readPixels(rgb, depth, view, &con_);
}

void Renderer::Resize(int width, int height) {
  if (!window_) return;  // an OSMesa buffer keeps its size
  width = std::max(16, width);
  height = std::max(16, height);
  if (width == opt_.width && height == opt_.height) return;
  opt_.width = width;
  opt_.height = height;
  layout_dirty_ = true;  // the overlays' places follow the frame
}

void Renderer::set_hud(bool on) {
  opt_.hud = on;
  layout_dirty_ = true;
}

void Renderer::set_tension_max(double T) {
  opt_.tension_max = T;
  layout_dirty_ = true;  // the scale's labels may change width
}

void Renderer::SetFreeCamera(const mjModel* m, bool free) {
  if (free && !free_camera_ && cam_.type != mjCAMERA_FREE) {
    // From a model's fixed camera: MuJoCo's default free view of the model.
    mjv_defaultFreeCamera(m, &cam_);
  }
  if (!free && free_camera_) {
    cam_ = options_cam_;
    filter_started_ = false;  // the follow/top camera starts again from the current state
  }
  free_camera_ = free;
}

}  // namespace mjtether::render
