// Our own reader of a TensorFlow Lite model file (the `.tflite` flatbuffer,
// TFLite's schema.fbs), for the MediaPipe hand models that
// filters/xnnpack_graph.h executes. It reads one subgraph: its tensors
// (shape, type, constant data), operators (builtin code, inputs, outputs and
// the options of the operators those models use) and the graph's inputs and
// outputs. Constant fp16 and fp32 data is converted to fp32 at load; a
// DEQUANTIZE of a constant fp16 tensor is folded away (its output becomes
// the fp32 constant), so the graph that remains is fp32 throughout.
//
// Contract: ReadTfliteModel() checks every offset against the buffer and
// throws Error("bad_model") naming the file and the field on a truncated or
// malformed file or an operator it does not know (the message lists it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace doasido::filters {

// TFLite's BuiltinOperator codes of the operators the reader knows.
enum class TfliteOp : int {
  kAdd = 0,
  kAveragePool2d = 1,
  kConcatenation = 2,
  kConv2d = 3,
  kDepthwiseConv2d = 4,
  kDequantize = 6,
  kFullyConnected = 9,
  kLogistic = 14,
  kMaxPool2d = 17,
  kMul = 18,
  kRelu = 19,
  kRelu6 = 21,
  kReshape = 22,
  kResizeBilinear = 23,
  kPad = 34,
  kMean = 40,
  kPrelu = 54,
};
// TFLite's ActivationFunctionType.
enum class TfliteActivation : int { kNone = 0, kRelu = 1, kReluN1To1 = 2, kRelu6 = 3 };

struct TfliteTensor {
  std::string name;
  std::vector<int> shape;
  int type = 0;               // TensorType: 0 fp32, 1 fp16, 2 int32
  std::vector<float> data;    // constant fp32/fp16 data as fp32; empty when computed
  std::vector<int32_t> ints;  // constant int32 data (shapes, paddings, axes)
  bool constant() const { return !data.empty() || !ints.empty(); }
};

// The options of one operator, the union of the fields the known operators
// have (TFLite keeps each in its own table).
struct TfliteOperator {
  TfliteOp op = TfliteOp::kAdd;
  std::vector<int> inputs, outputs;  // tensor indices; -1 = optional input absent
  bool same_padding = false;         // Padding SAME (else VALID)
  int stride_w = 1, stride_h = 1;
  int dilation_w = 1, dilation_h = 1;
  int filter_w = 0, filter_h = 0;  // pooling window
  int depth_multiplier = 1;
  TfliteActivation activation = TfliteActivation::kNone;
  int axis = 0;                   // concatenation
  bool keep_dims = false;         // mean
  bool align_corners = false;     // resize
  bool half_pixel_centers = false;
};

struct TfliteModel {
  std::string path;  // for error messages
  std::vector<TfliteTensor> tensors;
  std::vector<TfliteOperator> operators;
  std::vector<int> inputs, outputs;
};

// Reads `size` bytes at `data`; `path` names them in errors.
TfliteModel ReadTfliteModel(const std::uint8_t* data, std::size_t size, const std::string& path);
// Reads bytes [begin, end) of `file` (end 0 = to the end of the file).
TfliteModel ReadTfliteModel(const std::filesystem::path& file, std::size_t begin = 0,
                            std::size_t end = 0);

// The byte range [begin, end) of the file `name` packed in a MediaPipe
// solution's assets, as its loader script `loader` lists it
// ("/.../name", "start": B, "end": E); nothing when it is not listed.
std::optional<std::pair<std::size_t, std::size_t>> PackedFileRange(const std::filesystem::path& loader,
                                                                   const std::string& name);

// IEEE half to float.
float HalfToFloat(std::uint16_t h);

}  // namespace doasido::filters
