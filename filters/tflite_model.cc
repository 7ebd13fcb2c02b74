#include "filters/tflite_model.h"

#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <set>

#include "core/error.h"

namespace doasido::filters {

namespace {

// A bounds-checked view of a flatbuffer: tables are found through their
// vtables, vectors and strings through offsets, every read checked.
class FlatReader {
 public:
  FlatReader(const std::uint8_t* data, std::size_t size, const std::string& path)
      : data_(data), size_(size), path_(path) {}

  [[noreturn]] void Fail(const std::string& what) const {
    throw Error("bad_model", "not a readable TFLite model: " + what, {.file = path_});
  }
  template <typename T>
  T Read(std::size_t at, const char* field) const {
    if (at > size_ || size_ - at < sizeof(T)) Fail(std::string("offset past the end at ") + field);
    T v;
    std::memcpy(&v, data_ + at, sizeof(T));
    return v;
  }
  // Position of field `index` of the table at `table`, 0 when absent.
  std::size_t Field(std::size_t table, int index, const char* name) const {
    const std::size_t vtable = table - Read<std::int32_t>(table, name);
    const std::uint16_t vtable_size = Read<std::uint16_t>(vtable, name);
    const std::size_t slot = 4 + 2 * static_cast<std::size_t>(index);
    if (slot + 2 > vtable_size) return 0;
    const std::uint16_t offset = Read<std::uint16_t>(vtable + slot, name);
    return offset == 0 ? 0 : table + offset;
  }
  // The object an offset field points to.
  std::size_t Deref(std::size_t at, const char* name) const {
    return at + Read<std::uint32_t>(at, name);
  }
  // A vector field: its first element's position and its length.
  std::pair<std::size_t, std::uint32_t> Vector(std::size_t table, int index,
                                               const char* name) const {
    const std::size_t f = Field(table, index, name);
    if (f == 0) return {0, 0};
    const std::size_t v = Deref(f, name);
    const std::uint32_t n = Read<std::uint32_t>(v, name);
    if (n > size_ - v - 4) Fail(std::string("vector longer than the file at ") + name);
    return {v + 4, n};
  }
  std::size_t TableAt(std::size_t vector_begin, std::uint32_t i, const char* name) const {
    return Deref(vector_begin + 4 * static_cast<std::size_t>(i), name);
  }
  std::vector<int> Ints(std::size_t table, int index, const char* name) const {
    const auto [begin, n] = Vector(table, index, name);
    std::vector<int> out(n);
    for (std::uint32_t i = 0; i < n; ++i) out[i] = Read<std::int32_t>(begin + 4 * i, name);
    return out;
  }
  std::string String(std::size_t table, int index, const char* name) const {
    const auto [begin, n] = Vector(table, index, name);
    return std::string(reinterpret_cast<const char*>(data_ + begin), n);
  }
  template <typename T>
  T Scalar(std::size_t table, int index, T fallback, const char* name) const {
    const std::size_t f = Field(table, index, name);
    return f == 0 ? fallback : Read<T>(f, name);
  }
  const std::uint8_t* data() const { return data_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::string path_;
};

constexpr int kFloat32 = 0, kFloat16 = 1, kInt32 = 2;

const std::set<int> kKnownOps = {0, 1, 2, 3, 4, 6, 9, 14, 17, 18, 19, 21, 22, 23, 34, 40, 54};

void ReadConstantData(const FlatReader& r, std::size_t buffer, TfliteTensor* t) {
  const auto [begin, bytes] = r.Vector(buffer, 0, "buffers.data");
  if (bytes == 0) return;
  std::size_t count = 1;
  for (int d : t->shape) count *= static_cast<std::size_t>(std::max(d, 0));
  const std::size_t element = t->type == kFloat16 ? 2 : 4;
  if (count * element != bytes) {
    r.Fail("tensor " + t->name + " has " + std::to_string(bytes) + " bytes of data for " +
           std::to_string(count) + " elements (field buffers.data)");
  }
  const std::uint8_t* p = r.data() + begin;
  if (t->type == kFloat32) {
    t->data.resize(count);
    std::memcpy(t->data.data(), p, bytes);
  } else if (t->type == kFloat16) {
    t->data.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      std::uint16_t h;
      std::memcpy(&h, p + 2 * i, 2);
      t->data[i] = HalfToFloat(h);
    }
  } else if (t->type == kInt32) {
    t->ints.resize(count);
    std::memcpy(t->ints.data(), p, bytes);
  } else {
    r.Fail("tensor " + t->name + " has unsupported type " + std::to_string(t->type) +
           " (field tensors.type)");
  }
}

std::vector<TfliteTensor> ReadTensors(const FlatReader& r, std::size_t model,
                                      std::size_t subgraph) {
  const auto [buffers, buffer_count] = r.Vector(model, 4, "buffers");
  const auto [begin, n] = r.Vector(subgraph, 0, "tensors");
  std::vector<TfliteTensor> tensors(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::size_t t = r.TableAt(begin, i, "tensors");
    TfliteTensor& tensor = tensors[i];
    tensor.shape = r.Ints(t, 0, "tensors.shape");
    tensor.type = r.Scalar<std::int8_t>(t, 1, 0, "tensors.type");
    tensor.name = r.String(t, 3, "tensors.name");
    const std::uint32_t buffer = r.Scalar<std::uint32_t>(t, 2, 0, "tensors.buffer");
    if (buffer >= buffer_count) r.Fail("tensor " + tensor.name + " names a missing buffer");
    if (buffer != 0) ReadConstantData(r, r.TableAt(buffers, buffer, "buffers"), &tensor);
  }
  return tensors;
}

// The option fields of the known operators (TFLite schema tables
// Conv2DOptions, DepthwiseConv2DOptions, Pool2DOptions, ...).
void ReadOptions(const FlatReader& r, std::size_t options, TfliteOperator* o) {
  if (options == 0) return;
  auto activation = [&](int index) {
    return static_cast<TfliteActivation>(r.Scalar<std::int8_t>(options, index, 0, "activation"));
  };
  // Fields 0-2 of the convolution and pooling options: padding, strides.
  auto padding_and_strides = [&] {
    o->same_padding = r.Scalar<std::int8_t>(options, 0, 0, "padding") == 0;
    o->stride_w = r.Scalar<std::int32_t>(options, 1, 1, "stride_w");
    o->stride_h = r.Scalar<std::int32_t>(options, 2, 1, "stride_h");
  };
  switch (o->op) {
    case TfliteOp::kConv2d:
      padding_and_strides();
      o->activation = activation(3);
      o->dilation_w = r.Scalar<std::int32_t>(options, 4, 1, "dilation_w_factor");
      o->dilation_h = r.Scalar<std::int32_t>(options, 5, 1, "dilation_h_factor");
      break;
    case TfliteOp::kDepthwiseConv2d:
      padding_and_strides();
      o->depth_multiplier = r.Scalar<std::int32_t>(options, 3, 1, "depth_multiplier");
      o->activation = activation(4);
      o->dilation_w = r.Scalar<std::int32_t>(options, 5, 1, "dilation_w_factor");
      o->dilation_h = r.Scalar<std::int32_t>(options, 6, 1, "dilation_h_factor");
      break;
    case TfliteOp::kMaxPool2d:
    case TfliteOp::kAveragePool2d:
      padding_and_strides();
      o->filter_w = r.Scalar<std::int32_t>(options, 3, 1, "filter_width");
      o->filter_h = r.Scalar<std::int32_t>(options, 4, 1, "filter_height");
      o->activation = activation(5);
      break;
    case TfliteOp::kAdd:
    case TfliteOp::kMul:
    case TfliteOp::kFullyConnected:
      o->activation = activation(0);
      break;
    case TfliteOp::kConcatenation:
      o->axis = r.Scalar<std::int32_t>(options, 0, 0, "axis");
      o->activation = activation(1);
      break;
    case TfliteOp::kMean:
      o->keep_dims = r.Scalar<std::uint8_t>(options, 0, 0, "keep_dims") != 0;
      break;
    case TfliteOp::kResizeBilinear:
      o->align_corners = r.Scalar<std::uint8_t>(options, 2, 0, "align_corners") != 0;
      o->half_pixel_centers = r.Scalar<std::uint8_t>(options, 3, 0, "half_pixel_centers") != 0;
      break;
    default:
      break;
  }
}

std::vector<int> ReadOpcodes(const FlatReader& r, std::size_t model) {
  const auto [begin, n] = r.Vector(model, 1, "operator_codes");
  std::vector<int> codes(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::size_t c = r.TableAt(begin, i, "operator_codes");
    const int deprecated = r.Scalar<std::int8_t>(c, 0, 0, "deprecated_builtin_code");
    const int builtin = r.Scalar<std::int32_t>(c, 3, 0, "builtin_code");
    codes[i] = std::max(deprecated, builtin);
    if (!kKnownOps.count(codes[i])) {
      r.Fail("operator " + std::to_string(codes[i]) + " (TFLite BuiltinOperator) is not one " +
             "the reader knows (field operator_codes)");
    }
  }
  return codes;
}

// DEQUANTIZE of a constant: the output becomes the constant, the operator goes.
void FoldConstantDequantize(TfliteModel* m) {
  std::vector<TfliteOperator> kept;
  for (TfliteOperator& o : m->operators) {
    if (o.op == TfliteOp::kDequantize && o.inputs.size() == 1 &&
        m->tensors[o.inputs[0]].constant()) {
      m->tensors[o.outputs[0]].data = m->tensors[o.inputs[0]].data;
      continue;
    }
    kept.push_back(std::move(o));
  }
  m->operators = std::move(kept);
}

}  // namespace

float HalfToFloat(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000) << 16;
  std::uint32_t exponent = (h >> 10) & 0x1f, mantissa = h & 0x3ff, bits;
  if (exponent == 0x1f) {
    bits = sign | 0x7f800000u | (mantissa << 13);  // inf / nan
  } else if (exponent != 0) {
    bits = sign | ((exponent + 112) << 23) | (mantissa << 13);
  } else if (mantissa == 0) {
    bits = sign;
  } else {  // subnormal: normalise
    exponent = 113;
    while ((mantissa & 0x400) == 0) {
      mantissa <<= 1;
      --exponent;
    }
    bits = sign | (exponent << 23) | ((mantissa & 0x3ff) << 13);
  }
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

TfliteModel ReadTfliteModel(const std::uint8_t* data, std::size_t size, const std::string& path) {
  FlatReader r(data, size, path);
  if (size < 8 || std::memcmp(data + 4, "TFL3", 4) != 0) r.Fail("no TFL3 identifier");
  const std::size_t model = r.Deref(0, "root");
  TfliteModel m;
  m.path = path;
  const std::vector<int> opcodes = ReadOpcodes(r, model);
  const auto [subgraphs, subgraph_count] = r.Vector(model, 2, "subgraphs");
  if (subgraph_count != 1) r.Fail("expected one subgraph (field subgraphs)");
  const std::size_t subgraph = r.TableAt(subgraphs, 0, "subgraphs");
  m.tensors = ReadTensors(r, model, subgraph);
  m.inputs = r.Ints(subgraph, 1, "subgraphs.inputs");
  m.outputs = r.Ints(subgraph, 2, "subgraphs.outputs");
  const auto [ops, op_count] = r.Vector(subgraph, 3, "subgraphs.operators");
  const int tensor_count = static_cast<int>(m.tensors.size());
  for (std::uint32_t i = 0; i < op_count; ++i) {
    const std::size_t op = r.TableAt(ops, i, "operators");
    const std::uint32_t code = r.Scalar<std::uint32_t>(op, 0, 0, "operators.opcode_index");
    if (code >= opcodes.size()) r.Fail("operator names a missing opcode (field opcode_index)");
    TfliteOperator o;
    o.op = static_cast<TfliteOp>(opcodes[code]);
    o.inputs = r.Ints(op, 1, "operators.inputs");
    o.outputs = r.Ints(op, 2, "operators.outputs");
    for (int t : o.inputs) {
      if (t >= tensor_count) r.Fail("operator input past the tensors (field operators.inputs)");
    }
    for (int t : o.outputs) {
      if (t < 0 || t >= tensor_count) r.Fail("operator output past the tensors (field outputs)");
    }
    const std::size_t options = r.Field(op, 4, "operators.builtin_options");
    ReadOptions(r, options == 0 ? 0 : r.Deref(options, "builtin_options"), &o);
    m.operators.push_back(std::move(o));
  }
  for (int t : m.inputs) {
    if (t < 0 || t >= tensor_count) r.Fail("graph input past the tensors (field inputs)");
  }
  for (int t : m.outputs) {
    if (t < 0 || t >= tensor_count) r.Fail("graph output past the tensors (field outputs)");
  }
  FoldConstantDequantize(&m);
  return m;
}

TfliteModel ReadTfliteModel(const std::filesystem::path& file, std::size_t begin,
                            std::size_t end) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error("bad_model", "cannot open the model file", {.file = file.string()});
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
  if (end == 0) end = bytes.size();
  if (begin > end || end > bytes.size()) {
    throw Error("bad_model",
                "byte range " + std::to_string(begin) + ".." + std::to_string(end) +
                    " is past the end of the file (" + std::to_string(bytes.size()) + " bytes)",
                {.file = file.string()});
  }
  return ReadTfliteModel(bytes.data() + begin, end - begin, file.string());
}

std::optional<std::pair<std::size_t, std::size_t>> PackedFileRange(const std::filesystem::path& loader,
                                                                   const std::string& name) {
  std::ifstream in(loader);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  std::smatch m;
  const std::regex range("/" + std::regex_replace(name, std::regex("\\."), "\\.") +
                         R"re(", "start": (\d+), "end": (\d+))re");
  if (!std::regex_search(s, m, range)) return std::nullopt;
  return std::pair<std::size_t, std::size_t>{std::stoull(m[1].str()), std::stoull(m[2].str())};
}

}  // namespace doasido::filters
