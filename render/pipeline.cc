// Frames rendered in parallel and handed over in order (see pipeline.h).
#include "pipeline.h"

#include <sched.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

namespace mjtether::render {

namespace {

int UsableCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// One Renderer::Create or destruction at a time in the process (Create writes m's visual
// settings and MuJoCo loads its GL functions).
std::mutex& CreateMutex() {
  static std::mutex mu;
  return mu;
}

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int AutoRenderThreads() {
  // On 2 cores the pipeline does not pay: llvmpipe's own rasterizer threads already keep both
  // cores busy on one frame, and the workers only add contention (bench_render: 2 workers
  // cost about 1.1 x the serial path per frame; docs/rendering.md). Above that, one worker per
  // core up to 4 (each context with one rasterizer thread); not measured here.
  const int cores = UsableCores();
  return cores <= 2 ? 1 : std::min(cores, 4);
}

// One frame in flight: its state, its pixels and where it is in the pipeline.
struct Slot {
  enum State { kFree, kFilling, kQueued, kRendering, kDone };
  mjData* d = nullptr;
  std::vector<unsigned char> rgb;
  CameraPose pose;  // computed in order by the caller's thread (Renderer::NextPose)
  State state = kFree;
  Frame frame;
};

struct FramePipeline::Impl {
  mjModel* m = nullptr;
  FrameSink sink;

  // Serial path: one renderer in the caller's thread.
  std::unique_ptr<Renderer> serial;
  std::vector<unsigned char> serial_rgb;

  // Pipelined path. The cameras: a renderer in the caller's thread that only computes the
  // poses (its follow/top filter must see every frame, in order; it renders nothing).
  std::unique_ptr<Renderer> poses;
  // Everything below `mu` is guarded by it.
  std::vector<Slot> slots;
  std::vector<std::thread> workers;
  std::thread writer;
  std::mutex mu;
  std::condition_variable changed;  // any slot's state, `stop` or `failed`
  std::vector<int> queue;           // queued slots, oldest first
  long long submitted = 0;          // frames submitted
  long long delivered = 0;          // frames handed to the sink (the next one's index)
  bool stop = false;                // the threads must exit
  bool failed = false;              // the sink returned false
  int ready = 0;                    // workers whose renderer exists
  int samples = 0;                  // MSAA samples of the contexts
  std::string create_error;         // the first renderer's error

  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mu);
      stop = true;
    }
    changed.notify_all();
    for (std::thread& t : workers) t.join();
    if (writer.joinable()) writer.join();
    for (Slot& s : slots) mj_deleteData(s.d);
    if (poses) {
      std::lock_guard<std::mutex> create(CreateMutex());
      poses.reset();
    }
  }

  // A worker: makes its own renderer (one at a time: Renderer::Create writes m's visual
  // settings and MuJoCo loads its GL functions), then renders queued slots until stopped.
  // The renderer lives and dies in this thread, with its OSMesa context current here only.
  void Work(const RenderOptions& options, std::mutex* create_mu) {
    std::unique_ptr<Renderer> r;
    {
      std::lock_guard<std::mutex> create(*create_mu);
      std::string error;
      r = Renderer::Create(m, options, &error);
      std::lock_guard<std::mutex> lock(mu);
      if (!r && create_error.empty()) create_error = error;
      if (r) samples = r->samples();
      ++ready;
    }
    changed.notify_all();
    if (!r) return;
    for (;;) {
      Slot* s = nullptr;
      bool skip = false;  // the sink has stopped: nobody will look at the frame
      {
        std::unique_lock<std::mutex> lock(mu);
        changed.wait(lock, [&] { return stop || !queue.empty(); });
        if (stop) break;
        s = &slots[queue.front()];
        queue.erase(queue.begin());
        s->state = Slot::kRendering;
        skip = failed;
      }
      if (!skip) {
        const auto t0 = std::chrono::steady_clock::now();
        r->RenderAt(m, s->d, s->pose, s->rgb.data());
        s->frame.render_ms = MsSince(t0);
      }
      {
        std::lock_guard<std::mutex> lock(mu);
        s->state = Slot::kDone;
      }
      changed.notify_all();
    }
    std::lock_guard<std::mutex> create(*create_mu);
    r.reset();  // the context is destroyed in the thread it is current in
  }

  // The writer: hands the frames to the sink in submission order.
  void Write() {
    for (;;) {
      Slot* s = nullptr;
      bool skip = false;
      {
        std::unique_lock<std::mutex> lock(mu);
        changed.wait(lock, [&] { return stop || (s = Next()) != nullptr; });
        if (stop) return;
        skip = failed;
      }
      const bool ok = !skip && sink(s->frame);
      {
        std::lock_guard<std::mutex> lock(mu);
        if (!ok) failed = true;
        s->state = Slot::kFree;
        ++delivered;
      }
      changed.notify_all();
    }
  }

  // The slot holding the next frame to hand over if it is rendered, else nullptr (under mu).
  Slot* Next() {
    for (Slot& s : slots) {
      if (s.state == Slot::kDone && s.frame.index == delivered) return &s;
    }
    return nullptr;
  }
};

std::unique_ptr<FramePipeline> FramePipeline::Create(mjModel* m, const RenderOptions& render,
                                                     const PipelineOptions& options, FrameSink sink,
                                                     std::string* error) {
  if (options.threads < 0 || options.threads > 16) {
    *error = "render threads " + std::to_string(options.threads) +
             " out of range: 0 (automatic), 1 (serial) to 16";
    return nullptr;
  }
  if (options.slots < 0 || options.slots > 256) {
    *error = "pipeline slots " + std::to_string(options.slots) + " out of range [0, 256]";
    return nullptr;
  }
  std::unique_ptr<FramePipeline> p(new FramePipeline());
  p->impl_.reset(new Impl());
  Impl& impl = *p->impl_;
  impl.m = m;
  impl.sink = std::move(sink);
  p->threads_ = options.threads > 0 ? options.threads : AutoRenderThreads();
  p->width_ = render.width;
  p->height_ = render.height;
  const size_t bytes = static_cast<size_t>(3) * render.width * render.height;

  if (p->threads_ == 1) {
    impl.serial = Renderer::Create(m, render, error);
    if (!impl.serial) return nullptr;
    impl.serial_rgb.resize(bytes);
    p->samples_ = impl.serial->samples();
    return p;
  }

  // llvmpipe reads LP_NUM_THREADS when the process makes its first OSMesa context; each
  // context then gets that many rasterizer threads of its own.
  if (options.llvmpipe_threads >= 0) {
    setenv("LP_NUM_THREADS", std::to_string(options.llvmpipe_threads).c_str(), /*overwrite=*/0);
  }
  const int nslots = options.slots > 0 ? std::max(options.slots, p->threads_) : 2 * p->threads_ + 2;
  impl.slots.resize(nslots);
  for (Slot& s : impl.slots) {
    s.d = mj_makeData(m);
    if (!s.d) {
      *error = "MuJoCo: cannot allocate the pipeline's mjData";
      return nullptr;
    }
    s.rgb.resize(bytes);
  }
  std::mutex& create_mu = CreateMutex();
  {
    std::lock_guard<std::mutex> create(create_mu);
    RenderOptions pose_options = render;
    pose_options.samples = 0;  // draws nothing: no multisampled buffer
    impl.poses = Renderer::Create(m, pose_options, error);
  }
  if (!impl.poses) return nullptr;
  for (int i = 0; i < p->threads_; ++i) {
    impl.workers.emplace_back([&impl, &create_mu, render] { impl.Work(render, &create_mu); });
  }
  {
    std::unique_lock<std::mutex> lock(impl.mu);
    impl.changed.wait(lock, [&] { return impl.ready == p->threads_; });
    if (!impl.create_error.empty()) {
      *error = impl.create_error;
      lock.unlock();
      return nullptr;  // ~Impl stops the workers
    }
  }
  impl.writer = std::thread([&impl] { impl.Write(); });
  p->samples_ = impl.samples;
  return p;
}

FramePipeline::~FramePipeline() = default;

bool FramePipeline::Submit(mjData* d, long long tag, int flags) {
  Impl& impl = *impl_;
  if (impl.serial) {
    if (impl.failed) return false;
    Frame f;
    f.index = impl.submitted++;
    f.tag = tag;
    f.flags = flags;
    f.time = d->time;
    const auto t0 = std::chrono::steady_clock::now();
    impl.serial->Render(impl.m, d, impl.serial_rgb.data());
    f.render_ms = MsSince(t0);
    f.rgb = impl.serial_rgb.data();
    if (!impl.sink(f)) impl.failed = true;
    ++impl.delivered;
    return !impl.failed;
  }
  // A free slot (waiting while all are in flight).
  Slot* s = nullptr;
  {
    std::unique_lock<std::mutex> lock(impl.mu);
    impl.changed.wait(lock, [&] {
      if (impl.failed) return true;
      for (Slot& c : impl.slots) {
        if (c.state == Slot::kFree) {
          s = &c;
          return true;
        }
      }
      return false;
    });
    if (impl.failed) return false;
    s->state = Slot::kFilling;
  }
  // The copy is made outside the lock: the workers go on rendering meanwhile.
  mj_copyData(s->d, impl.m, d);
  s->pose = impl.poses->NextPose(impl.m, d);
  s->frame = Frame();
  s->frame.tag = tag;
  s->frame.flags = flags;
  s->frame.time = d->time;
  s->frame.rgb = s->rgb.data();
  {
    std::lock_guard<std::mutex> lock(impl.mu);
    s->frame.index = impl.submitted++;
    s->state = Slot::kQueued;
    impl.queue.push_back(static_cast<int>(s - impl.slots.data()));
  }
  impl.changed.notify_all();
  return true;
}

bool FramePipeline::Flush() {
  Impl& impl = *impl_;
  if (impl.serial) return !impl.failed;
  std::unique_lock<std::mutex> lock(impl.mu);
  impl.changed.wait(lock, [&] { return impl.delivered == impl.submitted; });
  return !impl.failed;
}

}  // namespace mjtether::render
