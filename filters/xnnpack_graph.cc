#include "filters/xnnpack_graph.h"

#include <xnnpack.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <set>

#include "core/error.h"

namespace doasido::filters {

struct XnnpackGraph::Concat {
  int output = 0;            // model tensor index
  std::vector<int> parts;    // model tensor indices, in order
  std::size_t outer = 1;     // product of the dimensions before the axis
};

namespace {

void InitializeOnce() {
  static std::once_flag once;
  static xnn_status status = xnn_status_success;
  std::call_once(once, [] { status = xnn_initialize(nullptr); });
  if (status != xnn_status_success) {
    throw Error("hand_detector_unavailable",
                "XNNPACK cannot start on this CPU (xnn_initialize failed)");
  }
}

std::size_t Elements(const std::vector<int>& shape) {
  std::size_t n = 1;
  for (int d : shape) n *= static_cast<std::size_t>(d);
  return n;
}

std::pair<float, float> Clamp(TfliteActivation a) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  switch (a) {
    case TfliteActivation::kRelu: return {0.f, inf};
    case TfliteActivation::kReluN1To1: return {-1.f, 1.f};
    case TfliteActivation::kRelu6: return {0.f, 6.f};
    default: return {-inf, inf};
  }
}

// Translates the model's operators into XNNPACK nodes, one value per
// model tensor (its index is the XNNPACK external id).
class Builder {
 public:
  Builder(const TfliteModel& m, xnn_subgraph_t s) : m_(m), s_(s), ids_(m.tensors.size(), kNone) {}

  void External(int t, std::uint32_t flags) { Define(t, m_.tensors[t].shape, flags); }

  void Add(const TfliteOperator& o) {
    const auto [lo, hi] = Clamp(o.activation);
    const int in = o.inputs.at(0), out = o.outputs.at(0);
    xnn_status st = xnn_status_success;
    switch (o.op) {
      case TfliteOp::kConv2d: {
        const std::vector<int>& f = m_.tensors[o.inputs.at(1)].shape;  // O, H, W, I
        st = xnn_define_convolution_2d(s_, 0, 0, 0, 0, f[1], f[2], o.stride_h, o.stride_w,
                                       o.dilation_h, o.dilation_w, 1, f[3], f[0], lo, hi, Id(in),
                                       Id(o.inputs.at(1)), Bias(o), Id(out), Padding(o));
        break;
      }
      case TfliteOp::kDepthwiseConv2d: {
        const std::vector<int>& f = m_.tensors[o.inputs.at(1)].shape;  // 1, H, W, C*m
        st = xnn_define_depthwise_convolution_2d(
            s_, 0, 0, 0, 0, f[1], f[2], o.stride_h, o.stride_w, o.dilation_h, o.dilation_w,
            o.depth_multiplier, m_.tensors[in].shape.at(3), lo, hi, Id(in), Id(o.inputs.at(1)),
            Bias(o), Id(out), Padding(o));
        break;
      }
      case TfliteOp::kMaxPool2d:
        st = xnn_define_max_pooling_2d(s_, 0, 0, 0, 0, o.filter_h, o.filter_w, o.stride_h,
                                       o.stride_w, 1, 1, lo, hi, Id(in), Id(out), Padding(o));
        break;
      case TfliteOp::kAveragePool2d:
        st = xnn_define_average_pooling_2d(s_, 0, 0, 0, 0, o.filter_h, o.filter_w, o.stride_h,
                                           o.stride_w, lo, hi, Id(in), Id(out), Padding(o));
        break;
      case TfliteOp::kAdd:
        st = xnn_define_add2(s_, lo, hi, Id(in), Id(o.inputs.at(1)), Id(out), 0);
        break;
      case TfliteOp::kMul:
        st = xnn_define_multiply2(s_, lo, hi, Id(in), Id(o.inputs.at(1)), Id(out), 0);
        break;
      case TfliteOp::kPrelu: {
        // XNNPACK wants the slope as [channels]; TFLite stores [1, 1, C].
        const TfliteTensor& slope = m_.tensors[o.inputs.at(1)];
        std::uint32_t slope_id = kNone;
        const std::size_t dims[1] = {slope.data.size()};
        Check(xnn_define_tensor_value(s_, xnn_datatype_fp32, 1, dims, slope.data.data(), kNone, 0,
                                      &slope_id), o);
        st = xnn_define_prelu(s_, Id(in), slope_id, Id(out), 0);
        break;
      }
      case TfliteOp::kRelu:
      case TfliteOp::kRelu6:
        st = xnn_define_clamp(s_, 0.f, o.op == TfliteOp::kRelu6 ? 6.f : Clamp({}).second, Id(in),
                              Id(out), 0);
        break;
      case TfliteOp::kLogistic:
        st = xnn_define_sigmoid(s_, Id(in), Id(out), 0);
        break;
      case TfliteOp::kPad: st = Pad(o); break;
      case TfliteOp::kReshape: {
        const std::vector<int>& shape = m_.tensors[out].shape;
        const std::vector<std::size_t> dims(shape.begin(), shape.end());
        st = xnn_define_static_reshape(s_, dims.size(), dims.data(), Id(in), Id(out), 0);
        break;
      }
      case TfliteOp::kResizeBilinear: {
        const std::vector<int32_t>& size = Ints(o.inputs.at(1), o);
        const std::uint32_t flags = o.align_corners        ? XNN_FLAG_ALIGN_CORNERS
                                    : o.half_pixel_centers ? 0
                                                           : XNN_FLAG_TENSORFLOW_LEGACY_MODE;
        st = xnn_define_static_resize_bilinear_2d(s_, size.at(0), size.at(1), Id(in), Id(out),
                                                  flags);
        break;
      }
      case TfliteOp::kMean: st = Mean(o); break;
      case TfliteOp::kFullyConnected:
        st = xnn_define_fully_connected(s_, lo, hi, Id(in), Id(o.inputs.at(1)), Bias(o), Id(out),
                                        XNN_FLAG_TENSORFLOW_RESHAPE_2D);
        break;
      default:
        Fail(o, "is not supported by the native runtime");
    }
    Check(st, o);
  }

 private:
  static constexpr std::uint32_t kNone = XNN_INVALID_VALUE_ID;

  [[noreturn]] void Fail(const TfliteOperator& o, const std::string& why) const {
    throw Error("bad_model",
                "operator " + std::to_string(static_cast<int>(o.op)) + " writing tensor " +
                    m_.tensors[o.outputs.at(0)].name + " " + why,
                {.file = m_.path});
  }
  void Check(xnn_status st, const TfliteOperator& o) const {
    if (st != xnn_status_success) Fail(o, "was refused by XNNPACK (status " + std::to_string(st) + ")");
  }
  const std::vector<int32_t>& Ints(int t, const TfliteOperator& o) const {
    if (t < 0 || m_.tensors[t].ints.empty()) Fail(o, "needs a constant int32 input");
    return m_.tensors[t].ints;
  }
  static std::uint32_t Padding(const TfliteOperator& o) {
    return o.same_padding ? XNN_FLAG_TENSORFLOW_SAME_PADDING : 0;
  }
  std::uint32_t Bias(const TfliteOperator& o) {
    return o.inputs.size() > 2 && o.inputs[2] >= 0 ? Id(o.inputs[2]) : kNone;
  }
  void Define(int t, const std::vector<int>& shape, std::uint32_t flags) {
    const std::vector<std::size_t> dims(shape.begin(), shape.end());
    const TfliteTensor& tensor = m_.tensors[t];
    const void* data = tensor.data.empty() ? nullptr : tensor.data.data();
    std::uint32_t id = 0;
    if (xnn_define_tensor_value(s_, xnn_datatype_fp32, dims.size(), dims.data(), data,
                                static_cast<std::uint32_t>(t), flags, &id) != xnn_status_success) {
      throw Error("bad_model", "XNNPACK refused tensor " + tensor.name, {.file = m_.path});
    }
    ids_[t] = id;
  }
  std::uint32_t Id(int t) {
    if (ids_[t] == kNone) Define(t, m_.tensors[t].shape, 0);
    return ids_[t];
  }
  xnn_status Pad(const TfliteOperator& o) {
    const std::vector<int32_t>& p = Ints(o.inputs.at(1), o);  // [dims, 2]
    std::vector<std::size_t> pre, post;
    for (std::size_t i = 0; i + 1 < p.size(); i += 2) {
      pre.push_back(p[i]);
      post.push_back(p[i + 1]);
    }
    if (pre.size() != m_.tensors[o.inputs[0]].shape.size()) Fail(o, "has paddings of wrong rank");
    return xnn_define_static_constant_pad(s_, pre.data(), post.data(), 0.f, Id(o.inputs[0]),
                                          Id(o.outputs[0]), 0);
  }
  // MEAN over height and width of NHWC = global average pooling; its output
  // is given the 4-D shape XNNPACK's pooling writes.
  xnn_status Mean(const TfliteOperator& o) {
    const std::vector<int32_t>& axes = Ints(o.inputs.at(1), o);
    const std::vector<int>& in = m_.tensors[o.inputs[0]].shape;
    if (in.size() != 4 || axes.size() != 2 || axes[0] != 1 || axes[1] != 2) {
      Fail(o, "is a MEAN not over height and width");
    }
    if (ids_[o.outputs[0]] == kNone) Define(o.outputs[0], {in[0], 1, 1, in[3]}, 0);
    const auto [lo, hi] = Clamp({});
    return xnn_define_global_average_pooling_2d(s_, lo, hi, Id(o.inputs[0]), Id(o.outputs[0]), 0);
  }

  const TfliteModel& m_;
  xnn_subgraph_t s_;
  std::vector<std::uint32_t> ids_;
};

}  // namespace

XnnpackGraph::XnnpackGraph(std::shared_ptr<const TfliteModel> model) : model_(std::move(model)) {
  InitializeOnce();
  Build();
  Setup();
}

XnnpackGraph::~XnnpackGraph() {
  if (runtime_ != nullptr) xnn_delete_runtime(runtime_);
}

void XnnpackGraph::Build() {
  const TfliteModel& m = *model_;
  if (m.inputs.size() != 1) throw Error("bad_model", "expected one input", {.file = m.path});
  xnn_subgraph_t subgraph = nullptr;
  if (xnn_create_subgraph(static_cast<std::uint32_t>(m.tensors.size()), 0, &subgraph) !=
      xnn_status_success) {
    throw Error("hand_detector_unavailable", "XNNPACK cannot create a subgraph");
  }
  std::unique_ptr<xnn_subgraph, decltype(&xnn_delete_subgraph)> owner(subgraph,
                                                                      xnn_delete_subgraph);
  Builder builder(m, subgraph);
  builder.External(m.inputs[0], XNN_VALUE_FLAG_EXTERNAL_INPUT);
  input_.assign(Elements(m.tensors[m.inputs[0]].shape), 0.f);
  std::map<int, std::size_t> output_index;
  for (std::size_t i = 0; i < m.outputs.size(); ++i) output_index[m.outputs[i]] = i;
  outputs_.resize(m.outputs.size());
  // A RESHAPE of a concatenation's result into a graph output only renames
  // its elements (row-major, as the SSD detector's box encodings): the
  // concatenation writes that graph output itself and the RESHAPE is dropped.
  std::map<int, int> reshaped;  // concatenation output -> graph output
  std::set<const TfliteOperator*> dropped;
  for (const TfliteOperator& r : m.operators) {
    if (r.op != TfliteOp::kReshape || !output_index.count(r.outputs[0])) continue;
    for (const TfliteOperator& c : m.operators) {
      if (c.op == TfliteOp::kConcatenation && c.outputs[0] == r.inputs.at(0)) {
        reshaped[c.outputs[0]] = r.outputs[0];
        dropped.insert(&r);
      }
    }
  }
  for (const TfliteOperator& o : m.operators) {
    if (o.op != TfliteOp::kConcatenation) continue;
    const int written = reshaped.count(o.outputs[0]) ? reshaped[o.outputs[0]] : o.outputs[0];
    if (!output_index.count(written)) {
      throw Error("bad_model", "a CONCATENATION that is not a graph output", {.file = m.path});
    }
    auto concat = std::make_unique<Concat>();
    concat->output = written;
    const std::vector<int>& shape = m.tensors[o.outputs[0]].shape;
    const int axis = o.axis < 0 ? o.axis + static_cast<int>(shape.size()) : o.axis;
    for (int d = 0; d < axis; ++d) concat->outer *= static_cast<std::size_t>(shape[d]);
    for (int t : o.inputs) {
      concat->parts.push_back(t);
      builder.External(t, XNN_VALUE_FLAG_EXTERNAL_OUTPUT);
      parts_.emplace_back(t, std::vector<float>(Elements(m.tensors[t].shape)));
    }
    concats_.push_back(std::move(concat));
  }
  for (std::size_t i = 0; i < m.outputs.size(); ++i) {
    outputs_[i].assign(Elements(m.tensors[m.outputs[i]].shape), 0.f);
    bool concatenated = false;
    for (const auto& c : concats_) concatenated |= c->output == m.outputs[i];
    if (!concatenated) builder.External(m.outputs[i], XNN_VALUE_FLAG_EXTERNAL_OUTPUT);
  }
  for (const TfliteOperator& o : m.operators) {
    if (o.op != TfliteOp::kConcatenation && !dropped.count(&o)) builder.Add(o);
  }
  if (xnn_create_runtime_v2(subgraph, nullptr, 0, &runtime_) != xnn_status_success) {
    throw Error("bad_model", "XNNPACK cannot build a runtime for the model", {.file = m.path});
  }
}

void XnnpackGraph::Setup() {
  const TfliteModel& m = *model_;
  std::vector<xnn_external_value> values;
  values.push_back({static_cast<std::uint32_t>(m.inputs[0]), input_.data()});
  for (auto& [t, buffer] : parts_) values.push_back({static_cast<std::uint32_t>(t), buffer.data()});
  for (std::size_t i = 0; i < m.outputs.size(); ++i) {
    bool concatenated = false;
    for (const auto& c : concats_) concatenated |= c->output == m.outputs[i];
    if (!concatenated) {
      values.push_back({static_cast<std::uint32_t>(m.outputs[i]), outputs_[i].data()});
    }
  }
  if (xnn_setup_runtime(runtime_, values.size(), values.data()) != xnn_status_success) {
    throw Error("bad_model", "XNNPACK cannot set up the model's inputs and outputs",
                {.file = m.path});
  }
}

void XnnpackGraph::Run() {
  if (xnn_invoke_runtime(runtime_) != xnn_status_success) {
    throw Error("hand_detector_failed", "XNNPACK failed to run " + model_->path);
  }
  const TfliteModel& m = *model_;
  for (const auto& c : concats_) {
    std::size_t out_index = 0;
    while (m.outputs[out_index] != c->output) ++out_index;
    float* out = outputs_[out_index].data();
    for (std::size_t o = 0; o < c->outer; ++o) {
      for (int t : c->parts) {
        const auto& part = std::find_if(parts_.begin(), parts_.end(),
                                        [t](const auto& p) { return p.first == t; })->second;
        const std::size_t chunk = part.size() / c->outer;
        std::memcpy(out, part.data() + o * chunk, chunk * sizeof(float));
        out += chunk;
      }
    }
  }
}

}  // namespace doasido::filters
