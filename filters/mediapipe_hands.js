// doasido's reference runtime for MediaPipe Hands' palm detector and
// 21-keypoint landmark model (TFLite files shipped in the npm package
// @mediapipe/hands): TFLite's WebAssembly runtime (@tensorflow/tfjs-tflite)
// on one thread. It runs the models only; the pre- and post-processing
// (anchors, non-maximum suppression, rotated crops, tracking) is doasido's
// C++ (filters/hand_landmarker.cc), shared with the native runtime
// (filters/xnnpack_graph.h), so the two runtimes see the same tensors.
// filters/hand_models_wasm.cc embeds this file and runs it with `node -e`,
// NODE_PATH pointing at the npm folder, and the two model files' names as
// arguments (palm_detection_<pair>.tflite hand_landmark_<pair>.tflite).
//
// Protocol, one request at a time:
//   stdin:  "palm\n" then 192*192*3 float32 (little-endian, RGB in [0, 1],
//           rows top to bottom), or "landmark\n" then 224*224*3 of them;
//           end of input ends the process.
//   stdout: "<ms> <count>\n" then <count> float32: the model's outputs in
//           the order of their names (Identity, Identity_1, ...), each
//           flattened; ms is the CPU time (user + system) the model took.
//   The first line is {"ready": true} or {"error": "..."} (then exit 1).
'use strict';
const fs = require('fs');
const path = require('path');
const vm = require('vm');

const kInputSize = { palm: 192, landmark: 224 };

// stdout carries the protocol; the libraries' notices are dropped, their
// errors go to stderr.
const reply = process.stdout.write.bind(process.stdout);
const stderr = console.error.bind(console);
console.log = console.info = console.warn = () => {};
console.error = (...args) => { if (!String(args[0]).startsWith('INFO:')) stderr(...args); };

function fail(message) {
  reply(JSON.stringify({ error: message }) + '\n');
  process.exit(1);
}

function packageDir(name) {
  return path.dirname(require.resolve(name + '/package.json'));
}

// tfjs-tflite loads its Emscripten module as a browser worker would; give
// it that world, single-threaded, with the WebAssembly read from disk.
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

function arrayBufferOf(buffer) {
  return buffer.buffer.slice(buffer.byteOffset, buffer.byteOffset + buffer.length);
}

// The palm detector is packed with other assets; its byte range is in the
// package's loader script.
function palmModelBytes(handsDir, palmFile) {
  const loader = fs.readFileSync(path.join(handsDir, 'hands_solution_packed_assets_loader.js'), 'utf8');
  const m = loader.match(new RegExp('/' + palmFile.replace(/\./g, '\\.') +
                                    '", "start": (\\d+), "end": (\\d+)'));
  if (!m) fail(palmFile + ' not listed in the @mediapipe/hands loader');
  const packed = fs.readFileSync(path.join(handsDir, 'hands_solution_packed_assets.data'));
  return arrayBufferOf(packed.subarray(Number(m[1]), Number(m[2])));
}

async function main() {
  const [palmFile, landmarkFile] = process.argv.slice(1);
  if (!palmFile || !landmarkFile) fail('usage: the palm and landmark model files as arguments');
  let tf, tflite, handsDir;
  try {
    handsDir = packageDir('@mediapipe/hands');
    shimBrowserWorker(path.join(packageDir('@tensorflow/tfjs-tflite'), 'wasm') + '/');
    tf = require('@tensorflow/tfjs-core');
    require('@tensorflow/tfjs-backend-cpu');
    tflite = require('@tensorflow/tfjs-tflite');
  } catch (e) {
    fail('cannot load the npm packages (scripts/setup.sh installs them): ' + e.message);
  }
  tflite.setWasmPath(path.join(packageDir('@tensorflow/tfjs-tflite'), 'wasm') + '/');
  await tf.setBackend('cpu');
  const models = {
    palm: await tflite.loadTFLiteModel(palmModelBytes(handsDir, palmFile), { numThreads: 1 }),
    landmark: await tflite.loadTFLiteModel(
        arrayBufferOf(fs.readFileSync(path.join(handsDir, landmarkFile))), { numThreads: 1 }),
  };
  reply(JSON.stringify({ ready: true }) + '\n');

  let pending = Buffer.alloc(0), model = null;
  const serve = () => {
    while (true) {
      if (!model) {
        const nl = pending.indexOf(10);
        if (nl < 0) return;
        model = pending.subarray(0, nl).toString().trim();
        pending = pending.subarray(nl + 1);
        if (!(model in kInputSize)) fail('bad request: ' + model);
      }
      const size = kInputSize[model], bytes = size * size * 3 * 4;
      if (pending.length < bytes) return;
      const input = new Float32Array(arrayBufferOf(pending.subarray(0, bytes)));
      const start = process.cpuUsage();
      const outputs = models[model].predict(tf.tensor(input, [1, size, size, 3]));
      const names = Object.keys(outputs).sort((a, b) => a.length - b.length || (a < b ? -1 : 1));
      const arrays = names.map((n) => outputs[n].dataSync());
      tf.dispose(Object.values(outputs));
      const used = process.cpuUsage(start), ms = (used.user + used.system) / 1e3;
      const count = arrays.reduce((s, a) => s + a.length, 0);
      const out = Buffer.alloc(count * 4);
      let at = 0;
      for (const a of arrays) for (const v of a) { out.writeFloatLE(v, at); at += 4; }
      reply(ms + ' ' + count + '\n');
      reply(out);
      pending = Buffer.from(pending.subarray(bytes));
      model = null;
    }
  };
  process.stdin.on('data', (chunk) => { pending = Buffer.concat([pending, chunk]); serve(); });
}

main().catch((e) => fail(String(e && e.stack || e)));
