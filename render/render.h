// Off-screen rendering of tethered scenes with MuJoCo's own renderer in an OSMesa context (no
// display, no libGL): the model's geoms, plus
//   - each tether as capsules between its nodes, coloured by segment tension on a fixed scale
//     [0, tension_max] (blue, cyan, green, yellow, red; red also above the scale); a slack
//     segment (no tension) is grey and half as thick;
//   - the seabed (a sand-coloured slab at the declared height, unless the model has a plane
//     there) and an arrow along the current, length proportional to its speed;
//   - a HUD: time, the tension at each end of every tether, the vehicle's depth, and the
//     labelled colour scale.
//
// Usage:
//   RenderOptions opt;  opt.width = 640; opt.height = 480; opt.tension_max = 200;
//   std::string error;
//   std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);   // sets m->vis sizes
//   mj_forward(m, d);                        // the tether at d->time
//   std::vector<unsigned char> rgb(3 * opt.width * opt.height);
//   r->Render(m, d, rgb.data());             // rows bottom-up, as OpenGL reads them
//
// One Renderer per thread: it makes its OSMesa context current on Create and Render.
#ifndef MJTETHER_PLUGIN_RENDER_H_
#define MJTETHER_PLUGIN_RENDER_H_

#include <mujoco/mujoco.h>

#include <memory>
#include <string>

namespace mjtether::render {

struct OsMesaApi;  // libOSMesa's functions (render.cc)

struct RenderOptions {
  int width = 1280;  // [pixel] even, in [16, 4096] (H.264 with yuv420p needs even sizes)
  int height = 720;  // [pixel] even, in [16, 4096]
  int samples = 4;   // multisampling (MSAA) samples, 0 to 16; 0 halves the software cost
  // "follow" (default): a free camera looking at the centre of the box bounding the tethers
  // and the vehicle, from the side of the current (across it), 12 degrees down, at a fixed
  // distance; "track:BODY": looks at BODY's origin from the same direction; otherwise the name
  // of a <camera> in the model.
  std::string camera = "follow";
  // [m] of the follow and track cameras; <= 0: 1.25 x the longest tether (follow), 15 x the
  // radius of the body's geoms, at least 1 m (track).
  double distance = 0;
  double tension_max = 0;    // [N] top of the colour scale; <= 0: 1 N
  std::string vehicle;       // body whose depth the HUD shows; empty: found (see Vehicle)
  bool hud = true;           // draw the HUD and the colour scale
  bool draw_tethers = true;  // draw the tethers (tests compare with and without)
};

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
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Renders d as it is (call mj_forward first so the tethers are at d->time) into rgb
  // (3 x width x height bytes, rows bottom-up); depth (width x height, [0, 1], 1 = far) too
  // if not null.
  void Render(const mjModel* m, mjData* d, unsigned char* rgb, float* depth = nullptr);

  // The scene and camera of the last Render (scene().camera[0] gives the projection).
  const mjvScene& scene() const { return scn_; }
  int width() const { return opt_.width; }
  int height() const { return opt_.height; }
  int samples() const { return con_.offSamples; }

 private:
  Renderer() = default;
  void PlaceCamera(const mjModel* m, const mjData* d);
  void Decorate(const mjModel* m, const mjData* d);
  void DrawHud(const mjModel* m, const mjData* d);
  void DrawWater();

  RenderOptions opt_;
  const OsMesaApi* gl_ = nullptr;  // libOSMesa's functions, opened at run time
  void* osmesa_ = nullptr;         // OSMesaContext
  std::unique_ptr<unsigned char[]> osmesa_buffer_;
  mjvScene scn_;
  mjrContext con_;
  mjvCamera cam_;
  mjvOption vopt_;
  bool scene_made_ = false, context_made_ = false;
  int vehicle_ = -1;             // body whose depth the HUD shows
  double follow_distance_ = 10;  // [m] of the follow and track cameras
  int track_body_ = -1;          // body the track camera looks at, or -1
  double follow_azimuth_ = 90;   // [deg]
  int seabed_geom_ = -1;         // a model plane at the seabed height, or -1
};

}  // namespace mjtether::render

#endif  // MJTETHER_PLUGIN_RENDER_H_
