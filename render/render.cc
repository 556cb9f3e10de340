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
#include <type_traits>
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
    get(api.PushAttrib, "glPushAttrib");
    get(api.PopAttrib, "glPopAttrib");
    get(api.Disable, "glDisable");
    get(api.Enable, "glEnable");
    get(api.DepthFunc, "glDepthFunc");
    get(api.DepthMask, "glDepthMask");
    get(api.Viewport, "glViewport");
    get(api.MatrixMode, "glMatrixMode");
    get(api.PushMatrix, "glPushMatrix");
    get(api.PopMatrix, "glPopMatrix");
    get(api.LoadIdentity, "glLoadIdentity");
    get(api.ShadeModel, "glShadeModel");
    get(api.Begin, "glBegin");
    get(api.End, "glEnd");
    get(api.Color3fv, "glColor3fv");
    get(api.Vertex3f, "glVertex3f");
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

}  // namespace

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

  // Follow distance: the longest tether should fit in the view; side-on to the current.
  double L = 0;
  for (int k = 0; k < TetherCount(m); ++k) L = std::max(L, GetTether(m, k)->params().length);
  r->follow_distance_ = o.distance > 0 ? o.distance
                        : L > 0        ? 1.25 * L
                                       : std::max(3.0, 2.0 * m->stat.extent);
  if (TetherCount(m) > 0) {
    const Vec3& u = GetTether(m, 0)->env().water.current;
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
    if (o.distance <= 0) r->follow_distance_ = std::max(1.0, 15 * BodySize(m, b));
    if (o.vehicle.empty()) r->vehicle_ = b;
  } else if (c != "follow") {
    const int id = mj_name2id(m, mjOBJ_CAMERA, c.c_str());
    if (id < 0) {
      *error =
          "--camera " + c + ": not 'follow', 'track:BODY' or the name of a <camera> in the model";
      return nullptr;
    }
    r->cam_.type = mjCAMERA_FIXED;
    r->cam_.fixedcamid = id;
  }
  r->cam_.distance = r->follow_distance_;
  r->cam_.azimuth = r->follow_azimuth_;
  r->cam_.elevation = -12;

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

  // The off-screen buffer is sized from the model: set it to the requested size, since a larger
  // viewport would be cropped silently.
  m->vis.global.offwidth = o.width;
  m->vis.global.offheight = o.height;
  m->vis.quality.offsamples = o.samples;

  int tether_geoms = 0;
  for (int k = 0; k < TetherCount(m); ++k) tether_geoms += GetTether(m, k)->segments();
  mjv_makeScene(m, &r->scn_, 2000 + m->ngeom + tether_geoms);
  r->scene_made_ = true;
  const int fontscale = o.height <= 500   ? mjFONTSCALE_100
                        : o.height <= 900 ? mjFONTSCALE_150
                                          : mjFONTSCALE_200;
  // Light the scene from the camera enough that a deep seabed is not black.
  m->vis.headlight.ambient[0] = m->vis.headlight.ambient[1] = m->vis.headlight.ambient[2] =
      std::max(m->vis.headlight.ambient[0], 0.25f);
  m->vis.headlight.diffuse[0] = m->vis.headlight.diffuse[1] = m->vis.headlight.diffuse[2] =
      std::max(m->vis.headlight.diffuse[0], 0.6f);
  mjr_makeContext(m, &r->con_, fontscale);
  r->context_made_ = true;
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
  if (osmesa_) {
    gl_->MakeCurrent(static_cast<OSMesaContext>(osmesa_), osmesa_buffer_.get(), GL_UNSIGNED_BYTE,
                     opt_.width, opt_.height);
  }
  if (context_made_) mjr_freeContext(&con_);
  if (scene_made_) mjv_freeScene(&scn_);
  if (osmesa_) gl_->DestroyContext(static_cast<OSMesaContext>(osmesa_));
}

// The follow camera looks at the centre of the box that bounds the tethers' nodes and the
// vehicle: it moves with the vehicle and keeps the whole tether in view. The track camera looks
// at its body's origin. Both are set from the state alone, so a frame does not depend on the
// frames before it (MuJoCo's own tracking camera filters its motion from frame to frame).
void Renderer::PlaceCamera(const mjModel* m, const mjData* d) {
  if (cam_.type != mjCAMERA_FREE) return;
  if (track_body_ >= 0) {
    for (int i = 0; i < 3; ++i) cam_.lookat[i] = d->xpos[3 * track_body_ + i];
    return;
  }
  Vec3 lo = Vec3::Constant(mjMAXVAL), hi = Vec3::Constant(-mjMAXVAL);
  auto add = [&](const double* p) {
    lo = lo.cwiseMin(Vec3(p));
    hi = hi.cwiseMax(Vec3(p));
  };
  for (int k = 0; k < TetherCount(m); ++k) {
    const double* x = NodePositions(m, d, k);
    if (!x) continue;
    // The deployed nodes only (with a winch, those before first_node are on the drum).
    for (int i = GetWinch(m, d, k).first_node; i < GetTether(m, k)->nodes(); ++i) add(x + 3 * i);
  }
  if (vehicle_ >= 0) add(d->xpos + 3 * vehicle_);
  const Vec3 lookat = lo.x() <= hi.x() ? Vec3(0.5 * (lo + hi)) : Vec3(m->stat.center);
  for (int i = 0; i < 3; ++i) cam_.lookat[i] = lookat[i];
}

// Tethers, seabed and the current arrow, added to the scene as decor geoms.
void Renderer::Decorate(const mjModel* m, const mjData* d) {
  std::vector<double> T;
  const mjvGLCamera& gl = scn_.camera[0];
  // Camera frame and a reference point in front of it at the follow distance.
  const Vec3 eye(gl.pos[0], gl.pos[1], gl.pos[2]);
  const Vec3 fwd(gl.forward[0], gl.forward[1], gl.forward[2]);
  const Vec3 up(gl.up[0], gl.up[1], gl.up[2]);
  const Vec3 right = fwd.cross(up);
  const double D = follow_distance_;
  const Vec3 ref = eye + D * fwd;
  const double half_h = D * 0.5 * (gl.frustum_top - gl.frustum_bottom) / gl.frustum_near;
  const double half_w = half_h * opt_.width / opt_.height;

  if (opt_.draw_tethers) {
    for (int k = 0; k < TetherCount(m); ++k) {
      const Tether& t = *GetTether(m, k);
      const double* x = NodePositions(m, d, k);
      if (!x) continue;
      T.resize(t.segments());
      GetTensions(m, d, k, T.data());
      const double radius = DrawnRadius(t, D);
      for (int j = GetWinch(m, d, k).first_node; j < t.segments(); ++j) {  // deployed only
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

  // Seabed: a slab whose top is at the seabed height, under the camera's reference point.
  if (w.has_seabed && seabed_geom_ < 0) {
    if (mjvGeom* g = NextGeom(&scn_)) {
      const double thick = 0.01 * D;
      const mjtNum size[3] = {4 * D, 4 * D, thick};
      const mjtNum pos[3] = {ref.x(), ref.y(), w.seabed - thick};
      const mjtNum mat[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      mjv_initGeom(g, mjGEOM_BOX, size, pos, mat, kSand);
      FinishDecor(g, &scn_);
    }
  }

  // Current: an arrow in the upper right of the view, 0.5 D per m/s (at most 0.4 D).
  const double speed = w.current.norm();
  if (speed > 0) {
    if (mjvGeom* g = NextGeom(&scn_)) {
      const Vec3 dir = w.current / speed;
      const double len = std::min(0.5 * D * speed, 0.4 * D);
      const Vec3 c = ref + 0.7 * half_h * up + 0.6 * half_w * right;
      const Vec3 a = c - 0.5 * len * dir, b = c + 0.5 * len * dir;
      mjv_initGeom(g, mjGEOM_ARROW, nullptr, nullptr, nullptr, kArrow);
      mjv_makeConnector(g, mjGEOM_ARROW, 0.012 * D, a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
      FinishDecor(g, &scn_);
    }
  }
}

void Renderer::DrawHud(const mjModel* m, const mjData* d) {
  const mjrRect view = {0, 0, opt_.width, opt_.height};
  std::string titles = "time", values;
  char buf[128];
  std::snprintf(buf, sizeof(buf), "%.2f s", d->time);
  values = buf;
  for (int k = 0; k < TetherCount(m); ++k) {
    const EndReactions r = GetReactions(m, d, k);
    const std::string name = TetherName(m, k);
    std::snprintf(buf, sizeof(buf), "\n%.1f N\n%.1f N", r.tension_a, r.tension_b);
    values += buf;
    titles += "\n" + name + ": T at end A (" + BodyName(m, EndBody(m, k, 0)) + ")\n" + name +
              ": T at end B (" + BodyName(m, EndBody(m, k, 1)) + ")";
    const WinchState w = GetWinch(m, d, k);
    if (w.present) {
      std::snprintf(buf, sizeof(buf), "\n%.2f m (%+.2f m/s)", w.length, w.payout_speed);
      values += buf;
      titles += "\n" + name + ": deployed (payout)";
    }
  }
  if (vehicle_ >= 0) {
    std::snprintf(buf, sizeof(buf), "\n%.2f m", -d->xpos[3 * vehicle_ + 2]);
    values += buf;
    titles += "\ndepth of " + BodyName(m, vehicle_);
    if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.has_seabed) {
      std::snprintf(buf, sizeof(buf), "\n%.2f m",
                    d->xpos[3 * vehicle_ + 2] - GetTether(m, 0)->env().water.seabed);
      values += buf;
      titles += "\naltitude";
    }
  }
  if (TetherCount(m) > 0 && GetTether(m, 0)->env().water.current.norm() > 0) {
    std::snprintf(buf, sizeof(buf), "\n%.2f m/s", GetTether(m, 0)->env().water.current.norm());
    values += buf;
    titles += "\ncurrent (white arrow)";
  }
  mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, view, titles.c_str(), values.c_str(), &con_);

  if (TetherCount(m) == 0) return;
  // Colour scale, bottom right: a ramp over [0, tension_max], ticks, and a slack swatch.
  const int W = opt_.width, H = opt_.height;
  const int ch = con_.charHeight;
  const int pad = std::max(4, H / 80);
  const int bar_w = W / 3, bar_h = std::max(6, H / 40);
  const int slack_w = std::max(6, W / 30);
  const int label_w = std::max(slack_w, W / 12);
  const int left = W - pad - label_w / 2 - bar_w;
  const int bottom = pad + ch + pad;
  const mjrRect panel = {left - 3 * pad - label_w, pad / 2, W - (left - 3 * pad - label_w),
                         bottom + bar_h + 2 * pad + ch};
  mjr_rectangle(panel, 0.0f, 0.0f, 0.0f, 0.55f);
  const int nstrip = 64;
  for (int i = 0; i < nstrip; ++i) {
    float rgba[4];
    TensionColor((i + 0.5) / nstrip * opt_.tension_max, opt_.tension_max, rgba);
    const int x0 = left + i * bar_w / nstrip, x1 = left + (i + 1) * bar_w / nstrip;
    mjr_rectangle({x0, bottom, x1 - x0, bar_h}, rgba[0], rgba[1], rgba[2], 1);
  }
  auto label = [&](int cx, int y, int w, const char* text) {
    mjr_label({cx - w / 2, y, w, ch + 2}, mjFONT_NORMAL, text, 0, 0, 0, 0, 1, 1, 1, &con_);
  };
  const double tmax = opt_.tension_max > 0 ? opt_.tension_max : 1;
  for (int i = 0; i <= 4; ++i) {
    std::snprintf(buf, sizeof(buf), "%g", tmax * i / 4);
    label(left + i * bar_w / 4, pad, label_w, buf);
  }
  label(left + bar_w / 2, bottom + bar_h + pad, bar_w, "segment tension [N]");
  const int sx = left - 2 * pad - label_w / 2;
  mjr_rectangle({sx - slack_w / 2, bottom + bar_h / 4, slack_w, bar_h / 2}, kSlack[0], kSlack[1],
                kSlack[2], 1);
  label(sx, pad, label_w, "slack");
}

// Water behind the scene: a vertical gradient drawn at the far plane, where the depth test lets
// it through only on pixels that nothing else covered.
void Renderer::DrawWater() {
  gl_->PushAttrib(GL_ALL_ATTRIB_BITS);
  gl_->Disable(GL_LIGHTING);
  gl_->Disable(GL_TEXTURE_2D);
  gl_->Disable(GL_BLEND);
  gl_->Disable(GL_CULL_FACE);
  gl_->Disable(GL_FOG);
  gl_->Enable(GL_DEPTH_TEST);
  gl_->DepthFunc(GL_LEQUAL);
  gl_->DepthMask(GL_FALSE);
  gl_->Viewport(0, 0, opt_.width, opt_.height);
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

void Renderer::Render(const mjModel* m, mjData* d, unsigned char* rgb, float* depth) {
  gl_->MakeCurrent(static_cast<OSMesaContext>(osmesa_), osmesa_buffer_.get(), GL_UNSIGNED_BYTE,
                   opt_.width, opt_.height);
  mjr_setBuffer(mjFB_OFFSCREEN, &con_);
  PlaceCamera(m, d);
  mjv_updateScene(m, d, &vopt_, nullptr, &cam_, mjCAT_ALL, &scn_);
  Decorate(m, d);
  const mjrRect view = {0, 0, opt_.width, opt_.height};
  mjr_render(view, &scn_, &con_);
  DrawWater();
  if (opt_.hud) DrawHud(m, d);

  mjr_readPixels(rgb, depth, view, &con_);
}

}  // namespace mjtether::render
