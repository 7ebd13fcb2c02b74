// A TFLite model (filters/tflite_model.h) executed by XNNPACK (Debian's
// libxnnpack-dev, the engine TFLite itself uses on CPU) through its
// subgraph API, fp32, on the calling thread (no thread pool: one graph per
// worker thread, the workers are the parallelism).
//
// The operators map one to one onto XNNPACK nodes, with two exceptions this
// XNNPACK snapshot (2022) needs: MEAN over height and width becomes global
// average pooling, and CONCATENATION (which it lacks) is done here after
// the run; it is allowed only where its result is a graph output, as in the
// palm detector's two heads, or is reshaped into one (a RESHAPE only
// renames elements: the Objectron detector's box encodings).
//
// Contract: the constructor throws Error("bad_model") naming the model file
// and the operator when the graph cannot be built; Run() throws
// Error("hand_detector_failed") when XNNPACK fails. Not thread-safe: one
// graph per thread.
#pragma once

#include <memory>
#include <vector>

#include "filters/tflite_model.h"

struct xnn_runtime;

namespace doasido::filters {

class XnnpackGraph {
 public:
  explicit XnnpackGraph(std::shared_ptr<const TfliteModel> model);
  ~XnnpackGraph();
  XnnpackGraph(const XnnpackGraph&) = delete;
  XnnpackGraph& operator=(const XnnpackGraph&) = delete;

  // The model's first input (fp32, NHWC): fill it, then Run().
  float* input() { return input_.data(); }
  std::size_t input_size() const { return input_.size(); }
  void Run();
  // Output `i` in the model's output order, fp32, row-major.
  const std::vector<float>& output(std::size_t i) const { return outputs_.at(i); }

 private:
  struct Concat;  // a CONCATENATION done after the run
  void Build();
  void Setup();

  std::shared_ptr<const TfliteModel> model_;
  xnn_runtime* runtime_ = nullptr;
  std::vector<float> input_;
  std::vector<std::vector<float>> outputs_;
  // XNNPACK's external outputs that are not model outputs (concat parts).
  std::vector<std::pair<int, std::vector<float>>> parts_;
  std::vector<std::unique_ptr<Concat>> concats_;
};

}  // namespace doasido::filters
