// The trajectory verification page: the clip's video beside a three.js
// replay of the robot trajectory, synchronised to the video's time.
#include "review/pages.h"
#include "review/verify_routes.h"

namespace doasido::review {
namespace {

const char* kStyle = R"css(
header a { color: #9fb7e0; }
main { display: grid; grid-template-columns: 220px 1fr 1fr 300px; gap: 12px; padding: 12px; }
#queue { list-style: none; margin: 0; padding: 0; max-height: 80vh; overflow: auto; }
#queue li { padding: 6px 8px; border-radius: 4px; cursor: pointer; border: 1px solid transparent; }
#queue li.current { background: #2d3646; border-color: #4b76c4; }
#queue li small { color: #9aa3b2; display: block; }
#video { width: 100%; background: #000; display: block; max-height: 60vh; }
#view { width: 100%; height: 60vh; display: block; background: #20242c; cursor: grab; }
aside { grid-row: 1 / 3; grid-column: 4; }
#controls { grid-column: 2 / 4; display: flex; gap: 8px; align-items: center; }
#scrub { flex: 1; }
aside section { background: #1f232b; border: 1px solid #333a45; border-radius: 6px;
                padding: 8px 10px; margin-bottom: 10px; }
aside h2 { font-size: 13px; margin: 0 0 6px; color: #9fb7e0; text-transform: uppercase; }
table { border-collapse: collapse; width: 100%; }
td { padding: 2px 4px; border-bottom: 1px solid #2c313b; }
td.bad { color: #ff8c8c; } td.good { color: #8fe3a8; }
#decision { display: grid; gap: 6px; grid-template-columns: 1fr 1fr; }
#decision textarea, #decision select { grid-column: 1 / 3; }
#status { color: #9aa3b2; }
.hint { color: #9aa3b2; font-size: 12px; }
)css";

const char* kBody = R"html(
<header><h1>doasido · verify trajectories</h1><span id="status"></span><span class="grow"></span>
<a href="/">flagged clips</a>
<label>reviewer <input id="reviewer" size="12"></label></header>
<main>
  <ul id="queue"></ul>
  <div><video id="video" muted playsinline preload="auto"></video></div>
  <div><canvas id="view"></canvas></div>
  <aside>
    <section><h2>Metrics</h2><table id="metrics"></table></section>
    <section><h2>Frame</h2><table id="frameinfo"></table></section>
    <section><h2>Decision</h2><div id="decision">
      <button class="accept" id="accept">Accept (a)</button>
      <button class="reject" id="reject">Reject (r)</button>
      <select id="reason"></select>
      <textarea id="reason_text" placeholder="optional note"></textarea></div>
      <p class="hint">space play/pause · ←/→ frame · j/k next/previous · 1-6 reason ·
      drag to orbit · wheel to zoom</p>
      <p class="hint"><span style="color:#6fd3ff">■</span> object pose from the reconstruction ·
      <span style="color:#ffc46f">■</span> human keypoints the hand followed (scaled)</p></section>
  </aside>
  <div id="controls"><button id="play">▶</button><input id="scrub" type="range" min="0" max="0"
    value="0" step="1"><span id="time"></span></div>
</main>
<script src="/vendor/three.min.js" nonce="NONCE"></script>
)html";

const char* kScript = R"js(
const cfg = JSON.parse(document.getElementById('cfg').textContent);
const REASONS = ['wrong_grasp', 'object_drift', 'jitter', 'penetration', 'wrong_hand', 'other'];
const state = { queue: [], index: -1, clip: null, scene: null, frame: 0, decisions: 0 };
window.doasidoVerify = state;
const $ = id => document.getElementById(id);
const video = $('video'), canvas = $('view'), scrub = $('scrub');
$('reviewer').value = cfg.reviewer || localStorage.getItem('doasido.reviewer') || '';
$('reviewer').addEventListener('change', e => localStorage.setItem('doasido.reviewer', e.target.value));
REASONS.forEach((r, i) => { const o = document.createElement('option'); o.value = r;
  o.textContent = (i + 1) + ' ' + r; $('reason').appendChild(o); });

// ---- three.js view: one group per MuJoCo body, posed per frame ----
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
const scene3 = new THREE.Scene();
scene3.background = new THREE.Color(0x20242c);
const camera = new THREE.PerspectiveCamera(45, 1, 0.005, 50);
scene3.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.4); sun.position.set(1, -1, 2); scene3.add(sun);
const orbit = { theta: -0.6, phi: 1.0, radius: 0.6, target: new THREE.Vector3() };
let groups = [], ghost = null, skeleton = null;
// OpenPose-21 bones: wrist to each finger's base, then along the finger.
const BONES = Array.from({ length: 20 }, (_, i) => i + 1).map(k => [k % 4 === 1 ? 0 : k - 1, k]);

function placeCamera() {
  const o = orbit, s = Math.sin(o.phi);
  camera.position.set(o.target.x + o.radius * s * Math.cos(o.theta),
                      o.target.y + o.radius * s * Math.sin(o.theta),
                      o.target.z + o.radius * Math.cos(o.phi));
  camera.up.set(0, 0, 1);
  camera.lookAt(o.target);
}
function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== w || canvas.height !== h) { renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1); camera.updateProjectionMatrix(); }
}
function geomObject(g, meshes, material) {
  const s = g.size; let geo, fix = null;
  if (g.type === 'box') geo = new THREE.BoxGeometry(2 * s[0], 2 * s[1], 2 * s[2]);
  else if (g.type === 'sphere') geo = new THREE.SphereGeometry(s[0], 16, 12);
  else if (g.type === 'ellipsoid') { geo = new THREE.SphereGeometry(1, 16, 12); fix = 'scale'; }
  else if (g.type === 'capsule') { geo = new THREE.CapsuleGeometry(s[0], 2 * s[1], 4, 12); fix = 'z'; }
  else if (g.type === 'cylinder') { geo = new THREE.CylinderGeometry(s[0], s[0], 2 * s[1], 16); fix = 'z'; }
  else if (g.type === 'plane') geo = new THREE.PlaneGeometry(2 * (s[0] || 1), 2 * (s[1] || 1));
  else if (g.type === 'mesh') { const m = meshes[g.mesh]; geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.Float32BufferAttribute(m.vertices, 3));
    geo.setIndex(m.faces); geo.computeVertexNormals(); }
  else return null;
  const mat = material || new THREE.MeshStandardMaterial({ color: new THREE.Color(g.rgba[0], g.rgba[1], g.rgba[2]),
    roughness: 0.6, metalness: 0.1 });
  const mesh = new THREE.Mesh(geo, mat);
  if (fix === 'z') mesh.geometry.rotateX(Math.PI / 2);   // three.js axes are +y; MuJoCo's +z
  if (fix === 'scale') mesh.scale.set(s[0], s[1], s[2]);
  const holder = new THREE.Group();
  holder.position.set(g.pos[0], g.pos[1], g.pos[2]);
  holder.quaternion.set(g.quat[1], g.quat[2], g.quat[3], g.quat[0]);
  holder.add(mesh);
  if (g.type === 'plane') mesh.material = new THREE.MeshStandardMaterial({ color: 0x3a4150 });
  return holder;
}
function buildScene(data) {
  for (const g of groups) scene3.remove(g);
  if (ghost) scene3.remove(ghost);
  if (skeleton) scene3.remove(skeleton);
  groups = []; ghost = null; skeleton = null;
  data.bodies.forEach(b => { const grp = new THREE.Group();
    for (const g of b.geoms) { const o = geomObject(g, data.meshes); if (o) grp.add(o); }
    scene3.add(grp); groups.push(grp); });
  // The reference object pose as a translucent ghost.
  if (data.object_body >= 0 && data.object_reference.length) {
    ghost = new THREE.Group();
    const mat = new THREE.MeshBasicMaterial({ color: 0x6fd3ff, transparent: true, opacity: 0.25,
                                              depthWrite: false });
    for (const g of data.bodies[data.object_body].geoms) { const o = geomObject(g, data.meshes, mat);
      if (o) ghost.add(o); }
    scene3.add(ghost);
  }
  // The human keypoints the hand followed: ghost joints and bones.
  if (data.reference_keypoints && data.reference_keypoints.some(k => k)) {
    skeleton = new THREE.Group();
    const mat = new THREE.MeshBasicMaterial({ color: 0xffc46f, transparent: true, opacity: 0.6,
                                              depthWrite: false });
    skeleton.userData.joints = [];
    for (let k = 0; k < 21; ++k) { const j = new THREE.Mesh(new THREE.SphereGeometry(0.004, 8, 6), mat);
      skeleton.add(j); skeleton.userData.joints.push(j); }
    const bones = new THREE.BufferGeometry();
    bones.setAttribute('position', new THREE.Float32BufferAttribute(new Float32Array(BONES.length * 6), 3));
    skeleton.userData.bones = new THREE.LineSegments(bones,
      new THREE.LineBasicMaterial({ color: 0xffc46f, transparent: true, opacity: 0.8 }));
    skeleton.add(skeleton.userData.bones);
    scene3.add(skeleton);
  }
  state.skeleton = skeleton;  // for tests and the console
  state.groups = groups;      // one per body, data.bodies' order
  // Orbit around the hand's mean position.
  const p = data.poses, c = new THREE.Vector3(); let n = 0;
  for (let f = 0; f < p.length; f += Math.max(1, Math.floor(p.length / 30))) {
    for (let b = 1; b < data.bodies.length; ++b) {
      if (!data.bodies[b].geoms.length || b === data.object_body) continue;
      c.add(new THREE.Vector3(p[f][7 * b], p[f][7 * b + 1], p[f][7 * b + 2])); ++n; } }
  if (n) orbit.target.copy(c.multiplyScalar(1 / n));
}
function poseFrame(f) {
  const d = state.scene; if (!d) return;
  f = Math.max(0, Math.min(d.frames - 1, f)); state.frame = f;
  const p = d.poses[f];
  groups.forEach((g, b) => { g.position.set(p[7 * b], p[7 * b + 1], p[7 * b + 2]);
    g.quaternion.set(p[7 * b + 4], p[7 * b + 5], p[7 * b + 6], p[7 * b + 3]); });
  if (ghost) { const r = d.object_reference[Math.min(f, d.object_reference.length - 1)];
    ghost.position.set(r[0], r[1], r[2]); ghost.quaternion.set(r[4], r[5], r[6], r[3]); }
  if (skeleton) { const k = d.reference_keypoints[Math.min(f, d.reference_keypoints.length - 1)];
    skeleton.visible = !!k;
    if (k) { skeleton.userData.joints.forEach((j, i) => j.position.set(k[3 * i], k[3 * i + 1], k[3 * i + 2]));
      const a = skeleton.userData.bones.geometry.attributes.position;
      BONES.forEach(([p, c], i) => { a.setXYZ(2 * i, k[3 * p], k[3 * p + 1], k[3 * p + 2]);
        a.setXYZ(2 * i + 1, k[3 * c], k[3 * c + 1], k[3 * c + 2]); });
      a.needsUpdate = true; } }
  scrub.value = f;
  $('time').textContent = (f / d.fps).toFixed(2) + ' s · frame ' + f + '/' + (d.frames - 1);
  const fe = d.fingertip_error[f];
  $('frameinfo').innerHTML = '';
  row($('frameinfo'), 'fingertip error', fe === undefined || fe === null ? '–' : (1000 * fe).toFixed(1) + ' mm');
  document.body.dataset.frame = String(f);
  render();
}
function render() { resize(); placeCamera(); renderer.render(scene3, camera); }
state.render = render;

// Orbit and zoom.
let drag = null;
canvas.addEventListener('pointerdown', e => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('pointermove', e => { if (!drag) return;
  orbit.theta -= (e.clientX - drag.x) * 0.01;
  orbit.phi = Math.max(0.05, Math.min(Math.PI - 0.05, orbit.phi - (e.clientY - drag.y) * 0.01));
  drag = { x: e.clientX, y: e.clientY }; render(); });
canvas.addEventListener('wheel', e => { e.preventDefault();
  orbit.radius = Math.max(0.05, Math.min(10, orbit.radius * Math.exp(e.deltaY * 0.001))); render(); },
  { passive: false });

// ---- video sync ----
function clipStart() { return state.clip ? state.clip.start_s || 0 : 0; }
function frameFromVideo() { return Math.round((video.currentTime - clipStart()) * state.scene.fps); }
function seekFrame(f) {
  poseFrame(f);
  if (state.clip && video.src) video.currentTime = clipStart() + state.frame / state.scene.fps;
}
video.addEventListener('timeupdate', () => { if (state.scene && !video.paused) poseFrame(frameFromVideo()); });
function tick() { if (state.scene && !video.paused) {
    if (frameFromVideo() >= state.scene.frames) video.currentTime = clipStart();
    poseFrame(frameFromVideo()); }
  requestAnimationFrame(tick); }
requestAnimationFrame(tick);
scrub.addEventListener('input', () => seekFrame(Number(scrub.value)));
function togglePlay() { if (video.paused) video.play().catch(() => {}); else video.pause(); }
$('play').addEventListener('click', togglePlay);

// ---- queue, metrics, decisions ----
function row(table, k, v, cls) { const tr = table.insertRow(); tr.insertCell().textContent = k;
  const td = tr.insertCell(); td.textContent = v; if (cls) td.className = cls; }
function showMetrics(m, d) {
  const t = $('metrics'); t.innerHTML = '';
  const flat = Object.assign({}, m, m.summary || {});
  const keys = Object.keys(flat).filter(k => /e_pos|e_rot|success|error|fingertip|object|rung/i.test(k) &&
                                            typeof flat[k] !== 'object');
  for (const k of keys) { const v = flat[k];
    row(t, k, typeof v === 'number' ? (Math.abs(v) < 10 ? v.toFixed(4) : v.toFixed(1)) : String(v),
        k.toLowerCase().includes('success') ? (v ? 'good' : 'bad') : ''); }
  row(t, 'embodiment', d.embodiment);
  row(t, 'frames', d.frames + ' at ' + d.fps + ' fps');
}
function renderQueue() {
  const ul = $('queue'); ul.innerHTML = '';
  state.queue.forEach((q, i) => { const li = document.createElement('li');
    li.textContent = (q.external_id || ('clip ' + q.clip_id));
    const s = document.createElement('small'); s.textContent = q.stage + ' · ' + q.verdict; li.appendChild(s);
    if (i === state.index) li.className = 'current';
    li.addEventListener('click', () => select(i)); ul.appendChild(li); });
  $('status').textContent = state.queue.length + ' to verify · ' + state.decisions + ' decided';
}
async function select(i) {
  if (i < 0 || i >= state.queue.length) { renderQueue(); return; }
  state.index = i; renderQueue();
  const q = state.queue[i];
  document.body.dataset.loaded = '0';
  const [clip, data] = await Promise.all([api('/api/clip/' + q.clip_id + '?stage=' + encodeURIComponent(q.stage)),
                                          api('/api/verify/scene/' + q.clip_id + '?stage=' + encodeURIComponent(q.stage))]);
  state.clip = clip; state.scene = data;
  buildScene(data);
  scrub.max = data.frames - 1;
  showMetrics(data.measurements || {}, data);
  video.src = clip.video_url;
  video.addEventListener('loadedmetadata', () => { video.currentTime = clipStart(); }, { once: true });
  poseFrame(0);
  document.body.dataset.clipId = String(q.clip_id);
  document.body.dataset.loaded = '1';
}
async function loadQueue() {
  state.queue = (await api('/api/verify/queue')).items;
  state.index = Math.min(Math.max(state.index, 0), state.queue.length - 1);
  if (state.queue.length) await select(state.index); else { renderQueue(); document.body.dataset.loaded = '1'; }
}
async function decide(decision) {
  const q = state.queue[state.index]; if (!q) return;
  const reviewer = $('reviewer').value.trim();
  if (!reviewer) { $('status').textContent = 'enter a reviewer name first'; $('reviewer').focus(); return; }
  try {
    await api('/api/verify/decision', { clip_id: q.clip_id, stage: q.stage, decision, reviewer,
      trajectory_sha256: state.scene ? state.scene.trajectory_sha256 : '',
      reason_code: decision === 'reject' ? $('reason').value : '', reason_text: $('reason_text').value });
  } catch (e) { $('status').textContent = e.message; return; }
  state.decisions += 1; document.body.dataset.decisions = String(state.decisions);
  $('reason_text').value = '';
  state.queue.splice(state.index, 1);
  if (state.index >= state.queue.length) state.index = state.queue.length - 1;
  if (state.queue.length) await select(state.index); else { state.scene = null; renderQueue(); }
}
$('accept').addEventListener('click', () => decide('accept'));
$('reject').addEventListener('click', () => decide('reject'));
document.addEventListener('keydown', e => {
  const tag = e.target.tagName;
  if (tag === 'INPUT' || tag === 'TEXTAREA' || tag === 'SELECT') { if (e.key === 'Escape') e.target.blur(); return; }
  if (e.key === 'a') decide('accept');
  else if (e.key === 'r') decide('reject');
  else if (e.key === 'j' || e.key === 'ArrowDown') select(state.index + 1);
  else if (e.key === 'k' || e.key === 'ArrowUp') select(state.index - 1);
  else if (e.key === ' ') { e.preventDefault(); togglePlay(); }
  else if (e.key === 'ArrowRight') { video.pause(); seekFrame(state.frame + 1); }
  else if (e.key === 'ArrowLeft') { video.pause(); seekFrame(state.frame - 1); }
  else if (e.key >= '1' && e.key <= String(REASONS.length)) $('reason').value = REASONS[Number(e.key) - 1];
  else return;
  e.preventDefault();
});
window.addEventListener('resize', render);
document.body.dataset.decisions = '0';
loadQueue().then(() => { document.body.dataset.ready = '1'; })
  .catch(e => { $('status').textContent = e.message; document.body.dataset.ready = 'error'; });
)js";

}  // namespace

std::string VerifyPage(const std::string& nonce, const Json& config) {
  std::string body = kBody;
  body.replace(body.find("NONCE"), 5, nonce);
  return ScriptedPage("doasido verify", nonce, std::string(kDecisionPageStyle) + kStyle, body,
                      config, kScript);
}

}  // namespace doasido::review
