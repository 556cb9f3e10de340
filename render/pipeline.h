// Frames rendered in parallel and handed over in order (docs/rendering.md).
//
// The caller (the simulation) submits the state of each frame. With 1 thread, Submit renders it
// and hands it to the sink at once, in the caller's thread: the serial path. With N >= 2
// threads, Submit copies the state (mj_copyData) into a free slot of a ring of preallocated
// mjData and returns; N workers, each with its own Renderer (its own OSMesa context), render the
// queued slots; a writer thread hands the rendered frames to the sink in submission order (to
// ffmpeg's pipe, for instance, while the next frames render). The follow and top cameras are a
// filter over the frames: Submit computes each frame's camera in the caller's thread, in
// order (Renderer::NextPose, no GL work), and the worker renders the copied state through it
// (Renderer::RenderAt), so both paths give the same bytes.
//
//   PipelineOptions po;                       // threads = 0: automatic
//   std::unique_ptr<FramePipeline> p = FramePipeline::Create(m, ropt, po, sink, &error);
//   for (...) { simulate; if (!p->Submit(d, k)) break; }   // false: the sink failed
//   bool ok = p->Flush();                     // every submitted frame handed over
//
// The sink runs in one thread at a time (the caller's with 1 thread, the writer's otherwise);
// m must outlive the pipeline and must not be changed while it runs.
#ifndef MJTETHER_RENDER_PIPELINE_H_
#define MJTETHER_RENDER_PIPELINE_H_

#include <mujoco/mujoco.h>

#include <functional>
#include <memory>
#include <string>

#include "render.h"

namespace mjtether::render {

struct PipelineOptions {
  // Render threads: 1 = serial (each frame rendered inside Submit); >= 2 = that many workers,
  // each with its own OSMesa context; 0 = automatic (AutoRenderThreads()). At most 16.
  int threads = 0;
  // Frames in flight (copied, queued, rendering or waiting for the sink); 0: 2 x threads + 2.
  int slots = 0;
  // llvmpipe's rasterizer threads per context (LP_NUM_THREADS) when the pipeline runs several
  // workers: set in the environment before the first OSMesa context of the process, unless
  // LP_NUM_THREADS is set already. -1: leave llvmpipe's default (one per core).
  int llvmpipe_threads = 1;
};

// Workers the automatic setting uses: 1 (serial) on up to 2 cores, where the pipeline was
// measured slower than the serial path; else the cores this process may run on
// (sched_getaffinity), at most 4.
int AutoRenderThreads();

// A rendered frame as the sink receives it.
struct Frame {
  long long index = 0;                 // submission order, from 0
  long long tag = 0;                   // the caller's (Submit's `tag`, e.g. the frame number)
  int flags = 0;                       // the caller's (Submit's `flags`, e.g. "write a still")
  double time = 0;                     // [s] d->time of the state rendered
  const unsigned char* rgb = nullptr;  // 3 x width x height bytes, rows bottom-up
  double render_ms = 0;                // [ms] wall time of Renderer::Render for this frame
};

// Receives each frame once, in submission order. Returns false to stop the pipeline (the sink
// reports its own error); later Submit and Flush calls then return false.
using FrameSink = std::function<bool(const Frame&)>;

class FramePipeline {
 public:
  // Creates the renderers (Renderer::Create, which sets m's off-screen buffer size) and starts
  // the threads. Returns nullptr with *error set (the first renderer's error, or threads out
  // of range).
  static std::unique_ptr<FramePipeline> Create(mjModel* m, const RenderOptions& render,
                                               const PipelineOptions& options, FrameSink sink,
                                               std::string* error);
  // Stops the threads; frames not yet handed to the sink are dropped (call Flush first).
  ~FramePipeline();
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  // Renders the state d (call mj_forward first, as for Renderer::Render). Serial: renders d
  // itself (MuJoCo's scene update may use its stack) and calls the sink before returning.
  // Pipelined: copies d and returns once the copy is queued (blocking while every slot is in
  // use). False if the sink has stopped the pipeline.
  bool Submit(mjData* d, long long tag, int flags = 0);

  // Waits until every submitted frame has been handed to the sink. False if the sink stopped
  // the pipeline. The pipeline can take more frames afterwards.
  bool Flush();

  int threads() const { return threads_; }
  int samples() const { return samples_; }  // MSAA samples of the contexts
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct Impl;
  FramePipeline() = default;
  int threads_ = 1, samples_ = 0, width_ = 0, height_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mjtether::render

#endif  // MJTETHER_RENDER_PIPELINE_H_
