// doasido's learned hand detector: MediaPipe Hands' palm detector and
// 21-keypoint landmark model (TFLite files shipped in the npm package
// @mediapipe/hands) run by TFLite's WebAssembly runtime (@tensorflow/tfjs-tflite)
// on one thread. The pre- and post-processing (anchors, weighted non-maximum
// suppression, the rotated hand crop, keypoints back to the frame, tracking
// a hand from its last keypoints) is ours; the numbers are MediaPipe's
// published graph options. filters/hand_landmarker.cc embeds this file and
// runs it with `node -e`, NODE_PATH pointing at the npm folder.
//
// Protocol, one request at a time:
//   stdin:  "frame <id> <width> <height>\n" then width*height*3 bytes of RGB,
//           rows top to bottom; "reset\n" forgets the tracked hands (a new
//           clip); end of input ends the process.
//   stdout: one JSON line per request:
//           {"id": <id>, "ms": <time>, "hands": [{"score", "right", "box":
//            [x1,y1,x2,y2], "keypoints": [[x,y,z] x 21], "world": [[x,y,z]
//            x 21]}]}
//           keypoints in frame pixels (z relative to the wrist, same scale),
//           world in metres about the hand's centre; "right" is the model's
//           probability that the hand is a right hand *as seen in a mirror*
//           (MediaPipe assumes selfie input); for camera footage swap it.
//   The first line is {"ready": true} or {"error": "..."} (then exit 1).
'use strict';
const fs = require('fs');
const path = require('path');
const vm = require('vm');

const kPalmSize = 192, kLandmarkSize = 224;
const kMinPalmScore = 0.5, kNmsIou = 0.3, kMinPresence = 0.5;
const kMaxHands = Number(process.env.DOASIDO_MAX_HANDS || 2);

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
function palmModelBytes(handsDir) {
  const loader = fs.readFileSync(path.join(handsDir, 'hands_solution_packed_assets_loader.js'), 'utf8');
  const m = loader.match(/palm_detection_full\.tflite", "start": (\d+), "end": (\d+)/);
  if (!m) fail('palm_detection_full.tflite not listed in the @mediapipe/hands loader');
  const packed = fs.readFileSync(path.join(handsDir, 'hands_solution_packed_assets.data'));
  return arrayBufferOf(packed.subarray(Number(m[1]), Number(m[2])));
}

// SSD anchors of the palm detector: strides 8, 16, 16, 16, two anchors per
// layer and cell, fixed size, centred in their cell.
function palmAnchors() {
  const anchors = [];
  const strides = [8, 16, 16, 16];
  let layer = 0;
  while (layer < strides.length) {
    let perCell = 0;
    const stride = strides[layer];
    while (layer < strides.length && strides[layer] === stride) { perCell += 2; ++layer; }
    const cells = Math.ceil(kPalmSize / stride);
    for (let y = 0; y < cells; ++y)
      for (let x = 0; x < cells; ++x)
        for (let a = 0; a < perCell; ++a) anchors.push([(x + 0.5) / cells, (y + 0.5) / cells]);
  }
  return anchors;
}

// Bilinear sample of an RGB frame into a size x size float tensor in [0, 1]
// through a map from output pixel centres to frame coordinates.
function sampleRgb(frame, size, map) {
  const out = new Float32Array(size * size * 3);
  const { width, height, rgb } = frame;
  for (let v = 0; v < size; ++v) {
    for (let u = 0; u < size; ++u) {
      const [fx, fy] = map(u + 0.5, v + 0.5);
      const x = fx - 0.5, y = fy - 0.5;
      const x0 = Math.floor(x), y0 = Math.floor(y);
      const ax = x - x0, ay = y - y0;
      const o = (v * size + u) * 3;
      for (let dy = 0; dy < 2; ++dy) {
        const yy = y0 + dy;
        if (yy < 0 || yy >= height) continue;
        const wy = dy ? ay : 1 - ay;
        for (let dx = 0; dx < 2; ++dx) {
          const xx = x0 + dx;
          if (xx < 0 || xx >= width) continue;
          const w = wy * (dx ? ax : 1 - ax) / 255;
          const i = (yy * width + xx) * 3;
          out[o] += w * rgb[i];
          out[o + 1] += w * rgb[i + 1];
          out[o + 2] += w * rgb[i + 2];
        }
      }
    }
  }
  return out;
}

function iou(a, b) {
  const ix = Math.max(0, Math.min(a[2], b[2]) - Math.max(a[0], b[0]));
  const iy = Math.max(0, Math.min(a[3], b[3]) - Math.max(a[1], b[1]));
  const inter = ix * iy;
  const union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
  return union > 0 ? inter / union : 0;
}

// Weighted non-maximum suppression: each kept palm is the score-weighted
// mean of the candidates overlapping the best one.
function weightedNms(candidates) {
  candidates.sort((a, b) => b.score - a.score);
  const kept = [];
  while (candidates.length) {
    const best = candidates[0];
    const group = candidates.filter((c) => iou(c.box, best.box) > kNmsIou);
    candidates = candidates.filter((c) => iou(c.box, best.box) <= kNmsIou);
    const total = group.reduce((s, c) => s + c.score, 0);
    const mean = (get) => group.reduce((s, c) => s + c.score * get(c), 0) / total;
    kept.push({
      score: best.score,
      box: best.box.map((_, i) => mean((c) => c.box[i])),
      keypoints: best.keypoints.map((_, k) => [mean((c) => c.keypoints[k][0]), mean((c) => c.keypoints[k][1])]),
    });
  }
  return kept;
}

function normalizeAngle(a) {
  return a - 2 * Math.PI * Math.floor((a + Math.PI) / (2 * Math.PI));
}

// A square rotated crop: centre, side and angle in frame pixels.
function cropFrom(cx, cy, w, h, rotation, scale, shiftY) {
  cx -= h * shiftY * Math.sin(rotation);
  cy += h * shiftY * Math.cos(rotation);
  return { cx, cy, side: Math.max(w, h) * scale, rotation };
}

// Angle that turns the wrist -> middle-finger direction upright.
function uprightAngle(wrist, middle) {
  return normalizeAngle(Math.PI / 2 - Math.atan2(-(middle[1] - wrist[1]), middle[0] - wrist[0]));
}

function detectPalms(model, tf, frame, anchors) {
  const scale = Math.min(kPalmSize / frame.width, kPalmSize / frame.height);
  const padX = (kPalmSize - frame.width * scale) / 2, padY = (kPalmSize - frame.height * scale) / 2;
  const input = sampleRgb(frame, kPalmSize, (u, v) => [(u - padX) / scale, (v - padY) / scale]);
  const outputs = model.predict(tf.tensor(input, [1, kPalmSize, kPalmSize, 3]));
  const raw = outputs['Identity'].dataSync(), logits = outputs['Identity_1'].dataSync();
  tf.dispose(Object.values(outputs));
  const toFrame = (x, y) => [(x * kPalmSize - padX) / scale, (y * kPalmSize - padY) / scale];
  const candidates = [];
  for (let i = 0; i < anchors.length; ++i) {
    const score = 1 / (1 + Math.exp(-Math.max(-100, Math.min(100, logits[i]))));
    if (score < kMinPalmScore) continue;
    const r = raw.subarray(i * 18, i * 18 + 18), [ax, ay] = anchors[i];
    const cx = r[0] / kPalmSize + ax, cy = r[1] / kPalmSize + ay;
    const w = r[2] / kPalmSize, h = r[3] / kPalmSize;
    const [x1, y1] = toFrame(cx - w / 2, cy - h / 2), [x2, y2] = toFrame(cx + w / 2, cy + h / 2);
    const keypoints = [];
    for (let k = 0; k < 7; ++k) keypoints.push(toFrame(r[4 + 2 * k] / kPalmSize + ax, r[5 + 2 * k] / kPalmSize + ay));
    candidates.push({ score, box: [x1, y1, x2, y2], keypoints });
  }
  // Palm keypoint 0 is the wrist, 2 the middle finger's base.
  return weightedNms(candidates).map((p) => cropFrom((p.box[0] + p.box[2]) / 2, (p.box[1] + p.box[3]) / 2,
      p.box[2] - p.box[0], p.box[3] - p.box[1], uprightAngle(p.keypoints[0], p.keypoints[2]), 2.6, -0.5));
}

function landmarks(model, tf, frame, crop) {
  const c = Math.cos(crop.rotation), s = Math.sin(crop.rotation);
  const toFrame = (u, v) => {
    const dx = (u / kLandmarkSize - 0.5) * crop.side, dy = (v / kLandmarkSize - 0.5) * crop.side;
    return [crop.cx + dx * c - dy * s, crop.cy + dx * s + dy * c];
  };
  const input = sampleRgb(frame, kLandmarkSize, toFrame);
  const outputs = model.predict(tf.tensor(input, [1, kLandmarkSize, kLandmarkSize, 3]));
  const screen = outputs['Identity'].dataSync(), presence = outputs['Identity_1'].dataSync()[0];
  const right = outputs['Identity_2'].dataSync()[0], world = outputs['Identity_3'].dataSync();
  tf.dispose(Object.values(outputs));
  if (presence < kMinPresence) return null;
  const keypoints = [], worldPoints = [];
  for (let k = 0; k < 21; ++k) {
    const [x, y] = toFrame(screen[3 * k], screen[3 * k + 1]);
    keypoints.push([x, y, screen[3 * k + 2] / kLandmarkSize * crop.side]);
    worldPoints.push([world[3 * k], world[3 * k + 1], world[3 * k + 2]]);
  }
  const xs = keypoints.map((p) => p[0]), ys = keypoints.map((p) => p[1]);
  const box = [Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)];
  return { score: presence, right, box, keypoints, world: worldPoints };
}

// The crop to look for a hand in the next frame: from the palm's keypoints
// (wrist, thumb base, finger bases and middle joints), upright, doubled.
function cropFromHand(hand) {
  const ids = [0, 1, 2, 3, 5, 6, 9, 10, 13, 14, 17, 18];
  const rotation = uprightAngle(hand.keypoints[0], hand.keypoints[9]);
  const c = Math.cos(rotation), s = Math.sin(rotation);
  let minU = Infinity, maxU = -Infinity, minV = Infinity, maxV = -Infinity;
  for (const i of ids) {
    const [x, y] = hand.keypoints[i];
    const u = x * c + y * s, v = -x * s + y * c;
    minU = Math.min(minU, u); maxU = Math.max(maxU, u);
    minV = Math.min(minV, v); maxV = Math.max(maxV, v);
  }
  const mu = (minU + maxU) / 2, mv = (minV + maxV) / 2;
  return cropFrom(mu * c - mv * s, mu * s + mv * c, maxU - minU, maxV - minV, rotation, 2.0, -0.1);
}

function detect(models, tf, frame, anchors, tracked) {
  const hands = [];
  const consider = (crop) => {
    const hand = landmarks(models.landmark, tf, frame, crop);
    if (hand && hands.every((h) => iou(h.box, hand.box) < 0.5)) hands.push(hand);
  };
  tracked.forEach(consider);
  if (hands.length < kMaxHands) {
    for (const crop of detectPalms(models.palm, tf, frame, anchors)) {
      if (hands.length >= kMaxHands) break;
      consider(crop);
    }
  }
  return hands;
}

async function main() {
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
    palm: await tflite.loadTFLiteModel(palmModelBytes(handsDir), { numThreads: 1 }),
    landmark: await tflite.loadTFLiteModel(
        arrayBufferOf(fs.readFileSync(path.join(handsDir, 'hand_landmark_full.tflite'))), { numThreads: 1 }),
  };
  const anchors = palmAnchors();
  reply(JSON.stringify({ ready: true }) + '\n');

  let pending = Buffer.alloc(0), header = null, tracked = [];
  const serve = () => {
    while (true) {
      if (!header) {
        const nl = pending.indexOf(10);
        if (nl < 0) return;
        const words = pending.subarray(0, nl).toString().trim().split(/\s+/);
        pending = pending.subarray(nl + 1);
        if (words[0] === 'reset') { tracked = []; continue; }
        if (words[0] !== 'frame' || words.length !== 4) fail('bad request: ' + words.join(' '));
        header = { id: Number(words[1]), width: Number(words[2]), height: Number(words[3]) };
      }
      const bytes = header.width * header.height * 3;
      if (pending.length < bytes) return;
      const frame = { width: header.width, height: header.height, rgb: pending.subarray(0, bytes) };
      const start = process.hrtime.bigint();
      const hands = detect(models, tf, frame, anchors, tracked);
      tracked = hands.map(cropFromHand);
      const ms = Number(process.hrtime.bigint() - start) / 1e6;
      reply(JSON.stringify({ id: header.id, ms, hands }) + '\n');
      pending = Buffer.from(pending.subarray(bytes));
      header = null;
    }
  };
  process.stdin.on('data', (chunk) => { pending = Buffer.concat([pending, chunk]); serve(); });
}

main().catch((e) => fail(String(e && e.stack || e)));
