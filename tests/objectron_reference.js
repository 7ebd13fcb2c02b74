// The tests' reference runtime for the Objectron models (tests/objects_box_keypoints_test.cc):
// TFLite's WebAssembly runtime (@tensorflow/tfjs-tflite, one thread) runs one
// model on input tensors the test wrote, so the native runtime
// (filters/xnnpack_graph.h) can be compared with it on the same tensors.
//
// Usage: node objectron_reference.js MODEL BEGIN END SIZE INPUTS OUTPUTS
//   MODEL: a .tflite file, or a packed-assets file with BEGIN..END its bytes
//   (END 0: the whole file); SIZE: the square input side; INPUTS: float32
//   tensors of SIZE*SIZE*3 back to back; OUTPUTS: written with, per input,
//   every output of the model (in the order of their names) flattened.
'use strict';
const fs = require('fs');
const path = require('path');
const vm = require('vm');

console.log = console.info = console.warn = () => {};

function packageDir(name) {
  return path.dirname(require.resolve(name + '/package.json'));
}

// tfjs-tflite loads its Emscripten module as a browser worker would.
function shimBrowserWorker(wasmDir) {
  globalThis.self = globalThis;
  globalThis.location = { origin: '', href: wasmDir };
  globalThis.importScripts = (url) => {
    url = url.replace('_simd_threaded.js', '_simd.js').replace('_threaded.js', '.js');
    vm.runInThisContext(fs.readFileSync(url, 'utf8'), { filename: url });
    const factory = globalThis.tflite_web_api_ModuleFactory;
    globalThis.tflite_web_api_ModuleFactory = (options) =>
        factory({ ...options, wasmBinary: fs.readFileSync(url.replace(/\.js$/, '.wasm')) });
  };
}

async function main() {
  const [model, begin, end, size, inputs, outputs] = process.argv.slice(2);
  const wasmDir = path.join(packageDir('@tensorflow/tfjs-tflite'), 'wasm') + '/';
  shimBrowserWorker(wasmDir);
  const tf = require('@tensorflow/tfjs-core');
  require('@tensorflow/tfjs-backend-cpu');
  const tflite = require('@tensorflow/tfjs-tflite');
  tflite.setWasmPath(wasmDir);
  await tf.setBackend('cpu');
  let bytes = fs.readFileSync(model);
  if (Number(end) > 0) bytes = bytes.subarray(Number(begin), Number(end));
  const m = await tflite.loadTFLiteModel(
      bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length), { numThreads: 1 });
  const data = fs.readFileSync(inputs);
  const n = Number(size) * Number(size) * 3;
  const all = new Float32Array(data.buffer, data.byteOffset, data.length / 4);
  const out = [];
  for (let at = 0; at + n <= all.length; at += n) {
    const result = m.predict(tf.tensor(all.slice(at, at + n), [1, Number(size), Number(size), 3]));
    const names = Object.keys(result).sort();
    for (const name of names) out.push(...result[name].dataSync());
    tf.dispose(Object.values(result));
  }
  fs.writeFileSync(outputs, Buffer.from(new Float32Array(out).buffer));
}

main().catch((e) => { process.stderr.write(String(e.stack || e) + '\n'); process.exit(1); });
