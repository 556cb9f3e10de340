// Off-screen rendering of tethered scenes with MuJoCo's own renderer in an OSMesa context (no
// display, no libGL): the model's geoms, plus
//   - each tether as capsules between its nodes, coloured by segment tension on a fixed scale
//     [0, tension_max] (blue, cyan, green, yellow, red; red also above the scale); a slack
//     segment (no tension) is grey and half as thick;
//   - the seabed (a sand-coloured slab at the declared height, unless the model has a plane
//     there), a translucent water surface at z = 0 when a tether end starts within 1 m of it,
//     fog toward the water's colour with distance (wet scenes), and an arrow along the current
//     (top right), length proportional to its speed (with a current profile, the current at
//     the depth of the view's centre);
//   - a HUD: time, the tension at each end of every tether, the vehicle's depth (top left), and
//     the labelled colour scale (bottom right), both sized from the frame with MuJoCo's font
//     metrics;
//   - a picture-in-picture close-up of the vehicle (bottom left) when it projects smaller than
//     RenderOptions::pip_min_px in the follow or top view.
// The follow and top cameras frame every tether node and every free body into the part of the
// frame that the HUD, the colour scale, the close-up and the current arrow leave free, and move
// smoothly: their look-at point and the logarithm of their distance follow that framing through
// a critically damped filter of time constant RenderOptions::smoothing (simulated time), then
// back off if that lag would leave a node or a vehicle outside the frame.  See docs/rendering.md.
//
// Usage:
//   RenderOptions opt;  opt.width = 640; opt.height = 480; opt.tension_max = 200;
//   std::string error;
//   std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);   // sets m->vis sizes
//   mj_forward(m, d);                        // the tether at d->time
//   std::vector<unsigned char> rgb(3 * opt.width * opt.height);
//   r->Render(m, d, rgb.data());             // rows bottom-up, as OpenGL reads them
//
// Render(m, d, rgb) = RenderAt(m, d, NextPose(m, d), rgb): NextPose advances the camera's filter
// (call it once per frame, in frame order) and costs no GL work, so a pipeline can compute the
// poses in order and render the frames elsewhere with RenderAt (render/pipeline.h does).
//
// One Renderer per thread: it makes its OSMesa context current on Create and Render. Several
// renderers may render in parallel threads.
#ifndef MJTETHER_PLUGIN_RENDER_H_
#define MJTETHER_PLUGIN_RENDER_H_

#include <mujoco/mujoco.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace mjtether::render {

struct OsMesaApi;  // libOSMesa's functions (render.cc)

struct RenderOptions {
  int width = 1280;  // [pixel] even, in [16, 4096] (H.264 with yuv420p needs even sizes)
  int height = 720;  // [pixel] even, in [16, 4096]
  int samples = 4;   // multisampling (MSAA) samples, 0 to 16; 0 halves the software cost
  // "follow" (default): a free camera from the side of the current (across it), 20 degrees
  // down, that frames every tether node and free body (see above); "top": the same from above;
  // "track:BODY": looks at BODY's origin from the follow direction; otherwise the name of a
  // <camera> in the model.
  std::string camera = "follow";
  // [m] of the follow, top and track cameras; <= 0 (auto): follow and top zoom to frame the
  // scene, track uses 8 x the radius of the body's geoms, at least 1 m.
  double distance = 0;
  double smoothing = 1;      // [s] time constant of the follow/top camera filter; 0: none
  double pip_min_px = 40;    // [pixel] close-up below this vehicle size (follow, top); 0: never
  double tension_max = 0;    // [N] top of the colour scale; <= 0: 1 N
  std::string vehicle;       // body whose depth the HUD shows; empty: found (see Vehicle)
  bool hud = true;           // draw the HUD and the colour scale
  bool draw_tethers = true;  // draw the tethers (tests compare with and without)
  // Each node as a white sphere and segment tensions [N] as labels (the viewer's O key).
  bool overlay = false;
};

// A GL context's function loader (glfwGetProcAddress, for instance).
using GlProcLoader = void* (*)(const char* name);

// A "nice" upper bound for a colour scale with ticks at quarters: the smallest 1, 2, 3, 4, 5, 6
// or 8 times a power of ten that is at least x (x > 0); 1 for x <= 0.
double NiceCeil(double x);

// The step at which frame k of a video at `fps` frames per second is taken, for a timestep h
// [s]: round(k / (fps h)). Scheduling by index keeps |step h - k/fps| <= h/2 for every k.
long long FrameStep(long long k, double fps, double h);

// Colour of tension T [N] on the scale [0, tension_max]: grey when T <= 0 (slack); otherwise
// the blue-cyan-green-yellow-red ramp at T / tension_max, clamped to red above the scale.
void TensionColor(double T, double tension_max, float rgba[4]);

// Writes rgb (3 x width x height bytes, rows bottom-up as Render gives them) to a PNG file.
// Returns false with *error set if the file cannot be written.
bool WritePng(const std::string& path, const unsigned char* rgb, int width, int height,
              std::string* error);

// A rectangle in pixels, from the bottom-left corner of the frame (as OpenGL counts).
struct Rect {
  int x = 0, y = 0, w = 0, h = 0;
  bool empty() const { return w <= 0 || h <= 0; }
  bool Contains(double px, double py) const {
    return px >= x && px <= x + w && py >= y && py <= y + h;
  }
};

// Where the overlays go in a frame (empty rectangles: not drawn).
struct Layout {
  Rect hud;    // top left: time, end tensions, depth
  Rect scale;  // bottom right: colour scale, its labels and the slack swatch
  Rect arrow;  // top right: the current arrow (only when there is a current)
  Rect pip;    // bottom left: the vehicle close-up, when shown
  Rect label;  // the "segment tension [N]" label, inside scale
};

// A free camera (MuJoCo's mjvCamera of type mjCAMERA_FREE): the frame the follow, top and track
// cameras use.
struct CameraPose {
  std::array<double, 3> lookat = {0, 0, 0};  // [m]
  double distance = 1;                       // [m]
  double azimuth = 90;                       // [deg]
  double elevation = -20;                    // [deg]
  bool pip = false;                          // the close-up is drawn
};

// Pixel (column, row from the bottom) where world point x projects through a free camera of
// vertical field of view fovy [deg] in a width x height frame.
std::array<double, 2> ProjectPose(const CameraPose& p, double fovy, int width, int height,
                                  const double x[3]);

// The vehicle of a scene: the body at end B of the first tether if it has a free joint, else
// the first body with a free joint, else -1.
int Vehicle(const mjModel* m);

class Renderer {
 public:
  // Creates the OSMesa context, sets m->vis.global.offwidth/offheight and
  // m->vis.quality.offsamples from the options (and raises the headlight to at least 0.25
  // ambient, 0.6 diffuse), and builds MuJoCo's scene and GL context.
  // Returns nullptr with *error set (options out of range, unknown camera or body, OSMesa or
  // off-screen buffer failure).
  static std::unique_ptr<Renderer> Create(mjModel* m, const RenderOptions& options,
                                          std::string* error);
  // The same scene, drawn into the window whose OpenGL context is current in the calling
  // thread (GLFW's, for `mjtether view`) instead of an OSMesa context: options.width and height
  // are its framebuffer's size, `load` gives the context's GL functions. The context must be
  // current for Render and when the renderer is destroyed.
  static std::unique_ptr<Renderer> CreateForWindow(mjModel* m, const RenderOptions& options,
                                                   GlProcLoader load, std::string* error);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders d as it is (call mj_forward first so the tethers are at d->time) into rgb
  // (3 x width x height bytes, rows bottom-up); depth (width x height, [0, 1], 1 = far) too
  // if not null.
  // rgb and depth may be null (a window's renderer draws into its window).
  void Render(const mjModel* m, mjData* d, unsigned char* rgb, float* depth = nullptr);

  // The camera for the frame at d->time: advances the follow/top filter (frames in order).
  CameraPose NextPose(const mjModel* m, const mjData* d);
  // Renders d through a pose from NextPose (ignored for a camera of the model and for a free
  // camera the caller moves).
  void RenderAt(const mjModel* m, mjData* d, const CameraPose& pose, unsigned char* rgb,
                float* depth = nullptr);

  // Interactive use (`mjtether view`), after Render:
  // - a line of text in the bottom-left corner, over what Render drew;
  void Caption(const std::string& left, const std::string& right);
  // - the pixels as they are now (3 x width x height bytes, rows bottom-up), caption included.
  void ReadPixels(unsigned char* rgb, float* depth = nullptr);
  // A window's new framebuffer size [pixel] (>= 16); the overlays are laid out again.
  void Resize(int width, int height);
  // The camera. Free: Render keeps it as the caller moved it (mjv_moveCamera); not free: the
  // camera of the options, placed from the state at each frame as in videos.
  mjvCamera* camera() { return &cam_; }
  void SetFreeCamera(const mjModel* m, bool free);
  bool free_camera() const { return free_camera_; }
  void set_overlay(bool on) { opt_.overlay = on; }
  bool overlay() const { return opt_.overlay; }
  void set_hud(bool on);
  bool hud() const { return opt_.hud; }
  void set_tension_max(double T);  // [N]
  double tension_max() const { return opt_.tension_max; }

  // The scene of the last Render; its camera is the main view's (scene().camera[0] and [1]
  // give the projection), also when a close-up was drawn after it.
  const mjvScene& scene() const { return scn_; }
  // The close-up's camera in the last Render (valid when its pose had pip set).
  const mjvGLCamera* pip_camera() const { return pip_rendered_ ? pip_camera_ : nullptr; }
  // The overlays' rectangles for the last pose (pip empty when no close-up).
  Layout layout() const;
  // Width [pixel] of text in the HUD's font (MuJoCo's metrics), and its line height.
  int TextWidth(const std::string& text) const;
  int LineHeight() const { return con_.charHeight; }
  // The close-up's camera for a pose (looks at the vehicle from the pose's direction).
  CameraPose PipPose(const mjModel* m, const mjData* d, const CameraPose& main) const;
  int width() const { return opt_.width; }
  int height() const { return opt_.height; }
  int samples() const { return con_.offSamples; }

 private:
  Renderer() = default;
  static std::unique_ptr<Renderer> CreateIn(mjModel* m, const RenderOptions& options,
                                            GlProcLoader window, std::string* error);
  void BeginFrame();
  void DrawOverlay(const mjModel* m, const mjData* d, double distance);
  void DrawOverlayLabels(const mjModel* m, const mjData* d);
  CameraPose Target(const mjModel* m, const mjData* d, bool pip) const;
  void Decorate(const mjModel* m, const mjData* d, double distance, bool overlays);
  void DrawHud(const mjModel* m, const mjData* d);
  void DrawWater(const Rect& r);
  void Fog(double distance);
  void Text(int x, int y, const std::string& text, float gray);
  void ComputeLayout(const mjModel* m);
  double VehiclePixels(const mjModel* m, const mjData* d, const CameraPose& p) const;

  RenderOptions opt_;
  const OsMesaApi* gl_ = nullptr;  // libOSMesa's functions, opened at run time
  void* osmesa_ = nullptr;         // OSMesaContext
  std::unique_ptr<unsigned char[]> osmesa_buffer_;
  mjvScene scn_;
  mjrContext con_;
  mjvCamera cam_;
  mjvOption vopt_;
  bool scene_made_ = false, context_made_ = false;
  int vehicle_ = -1;                 // body whose depth the HUD shows
  double follow_distance_ = 10;      // [m] of the track camera (and follow/top when fixed)
  int track_body_ = -1;              // body the track camera looks at, or -1
  bool wet_ = false;                 // water declared: fog
  bool has_surface_ = false;         // a tether end starts at the surface: draw it at z = 0
  bool top_ = false;                 // "top" camera
  double follow_azimuth_ = 90;       // [deg]
  int seabed_geom_ = -1;             // a model plane at the seabed height, or -1
  std::vector<int> free_bodies_;     // bodies with a free joint: framed with the tethers
  std::vector<double> body_radius_;  // [m] per body: sphere holding its geoms (BodySize)
  // Overlays (ComputeLayout): fixed for the run, except the close-up shown or not.
  Layout layout_;
  bool pip_shown_ = false;
  mjvGLCamera pip_camera_[1];
  bool pip_rendered_ = false;
  // Filter state of the follow/top camera: look-at [m] and log(distance), their rates [/s].
  bool filter_started_ = false;
  double filter_time_ = 0;  // [s] simulated time of the last pose
  double state_[4] = {0, 0, 0, 0}, rate_[4] = {0, 0, 0, 0};
  bool window_ = false;                   // drawing into a window's context, not OSMesa's
  std::unique_ptr<OsMesaApi> window_gl_;  // the window context's GL functions
  mjvCamera options_cam_;                 // the camera of the options, as Create set it
  bool free_camera_ = false;              // the caller moves cam_
  bool layout_dirty_ = false;             // size, HUD or scale changed: ComputeLayout again
  double current_shown_ = 0;              // [m/s] the current's speed the last arrow showed
};

}  // namespace mjtether::render

#endif  // MJTETHER_PLUGIN_RENDER_H_
