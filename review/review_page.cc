// The flagged-clip queue page.
#include "review/pages.h"

namespace doasido::review {
namespace {

const char* kStyle = R"css(
button { cursor: pointer; }
main { display: grid; grid-template-columns: 240px 1fr 340px; gap: 12px; padding: 12px; }
#queue { list-style: none; margin: 0; padding: 0; max-height: 80vh; overflow: auto; }
#queue li { padding: 6px 8px; border-radius: 4px; cursor: pointer; border: 1px solid transparent; }
#queue li.current { background: #2d3646; border-color: #4b76c4; }
#queue li small { color: #9aa3b2; display: block; }
#stage { position: relative; background: #000; }
#video { width: 100%; display: block; max-height: 62vh; }
#overlay { position: absolute; left: 0; top: 0; pointer-events: none; }
#timeline { position: relative; height: 18px; background: #262b35; margin-top: 6px;
            border-radius: 3px; overflow: hidden; }
#timeline .trim { position: absolute; top: 0; bottom: 0; background: #2c5a3a; }
#timeline .cut { position: absolute; top: 0; bottom: 0; width: 2px; background: #ff5d5d; }
#timeline .head { position: absolute; top: 0; bottom: 0; width: 2px; background: #fff; }
#controls { display: flex; gap: 8px; margin-top: 8px; flex-wrap: wrap; align-items: center; }
#decision { display: grid; gap: 6px; margin-top: 10px; grid-template-columns: 1fr 1fr; }
#decision textarea { grid-column: 1 / 3; min-height: 40px; }
#decision .hint { color: #9aa3b2; align-self: center; }
aside section { background: #1f232b; border: 1px solid #333a45; border-radius: 6px;
                padding: 8px 10px; margin-bottom: 10px; }
aside h2 { font-size: 13px; margin: 0 0 6px; color: #9fb7e0; text-transform: uppercase; }
table { border-collapse: collapse; width: 100%; }
td, th { padding: 2px 4px; border-bottom: 1px solid #2c313b; text-align: left;
         vertical-align: top; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.over-reject td { color: #ff8a8a; } tr.over-flag td { color: #ffd27a; }
kbd { background: #333a45; border-radius: 3px; padding: 0 4px; font-size: 12px; }
#toast { position: fixed; right: 16px; bottom: 16px; background: #2d3646; padding: 8px 12px;
         border-radius: 6px; opacity: 0; transition: opacity .2s; }
#toast.show { opacity: 1; }
#empty { padding: 40px; text-align: center; color: #9aa3b2; }
.hidden { display: none !important; }
pre { white-space: pre-wrap; word-break: break-word; margin: 0; font-size: 12px; }
)css";

const char* kBody = R"html(
<header>
  <h1>doasido review</h1>
  <span id="count">loading queue…</span>
  <button id="reload" title="fetch the queue again">reload <kbd>g</kbd></button>
  <span class="grow"></span>
  <label>Reviewer <input id="reviewer" size="14" autocomplete="off"></label>
</header>
<main>
  <nav><ul id="queue"></ul></nav>
  <div>
    <div id="empty" class="hidden">No flagged clips are waiting for review.</div>
    <div id="player">
      <div id="stage"><video id="video" muted playsinline preload="auto"></video>
        <canvas id="overlay"></canvas></div>
      <div id="timeline" title="clip span (green), cut positions (red), playhead (white)"></div>
      <div id="controls">
        <button id="prev">◀ prev <kbd>k</kbd></button>
        <button id="play">play / pause <kbd>space</kbd></button>
        <button id="next">next <kbd>j</kbd> ▶</button>
        <span id="frame"></span>
      </div>
      <div id="decision">
        <select id="reason" title="reason code">
          <option value="">— reason —</option>
@REASONS@        </select>
        <label for="note" class="hint">free-text reason (optional), stored after the code</label>
        <textarea id="note" aria-label="free-text reason"></textarea>
        <button id="accept" class="accept">Accept <kbd>a</kbd></button>
        <button id="reject" class="reject">Reject <kbd>r</kbd></button>
      </div>
    </div>
  </div>
  <aside>
    <section><h2>Clip</h2><div id="info"></div></section>
    <section><h2>Scores</h2><table id="scores"></table></section>
    <section><h2>Every stage</h2><table id="stages"></table></section>
    <section><h2>Measurements</h2><pre id="summary"></pre></section>
    <section id="help"><h2>Keys</h2>
      <table>
        <tr><td><kbd>a</kbd></td><td>accept (the clip moves on to the next stage)</td></tr>
        <tr><td><kbd>r</kbd></td><td>reject with the selected reason</td></tr>
        <tr><td><kbd>j</kbd> <kbd>↓</kbd></td><td>next clip</td></tr>
        <tr><td><kbd>k</kbd> <kbd>↑</kbd></td><td>previous clip</td></tr>
        <tr><td><kbd>space</kbd></td><td>play / pause</td></tr>
        <tr><td><kbd>←</kbd> <kbd>→</kbd></td><td>one frame back / forward</td></tr>
        <tr><td><kbd>1</kbd>…<kbd>9</kbd></td><td>pick reason 1…9</td></tr>
        <tr><td><kbd>g</kbd></td><td>reload the queue</td></tr>
        <tr><td><kbd>Esc</kbd></td><td>leave a text field</td></tr>
      </table>
    </section>
  </aside>
</main>
<div id="toast"></div>
)html";

const char* kScript = R"js(
'use strict';
const cfg = JSON.parse(document.getElementById('cfg').textContent);
const $ = (id) => document.getElementById(id);
const video = $('video'), canvas = $('overlay'), ctx = canvas.getContext('2d');
const state = { queue: [], index: 0, clip: null, busy: false, decisions: 0, ready: false,
                byFrame: new Map(), seq: 0 };
window.doasidoState = state;

function toast(text) {
  const t = $('toast'); t.textContent = text; t.classList.add('show');
  clearTimeout(toast.timer); toast.timer = setTimeout(() => t.classList.remove('show'), 2500);
}


function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  if (cls) e.className = cls;
  return e;
}

function renderQueue() {
  const ul = $('queue'); ul.replaceChildren();
  state.queue.forEach((q, i) => {
    const li = el('li', '#' + q.clip_id + ' ' + (q.external_id || ''));
    li.appendChild(el('small', q.stage + (q.reason ? ' · ' + q.reason : '')));
    if (i === state.index) li.className = 'current';
    li.dataset.clipId = q.clip_id;
    li.addEventListener('click', () => show(i));
    ul.appendChild(li);
  });
  $('count').textContent = state.queue.length + ' flagged clip' +
      (state.queue.length === 1 ? '' : 's') + ' waiting';
  $('empty').classList.toggle('hidden', state.queue.length > 0);
  $('player').classList.toggle('hidden', state.queue.length === 0);
}

const reasonForStage = cfg.reason_for_stage || {};

function fmt(v) {
  if (typeof v === 'number') return Number.isInteger(v) ? String(v) : v.toPrecision(4);
  return typeof v === 'object' ? JSON.stringify(v) : String(v);
}

function renderPanel(c) {
  const info = $('info'); info.replaceChildren();
  const t = el('table');
  const rows = [['clip', '#' + c.clip_id + ' ' + (c.external_id || '')], ['stage', c.stage],
    ['flag reason', c.reason || '—'], ['video', (c.width || '?') + '×' + (c.height || '?') +
    ' @ ' + (c.fps ? c.fps.toFixed(2) : '?') + ' fps'],
    ['span', c.start_s.toFixed(2) + ' – ' +
             (c.end_s != null ? c.end_s.toFixed(2) : 'end') + ' s'],
    ['boxes', String(c.detections.length)]];
  for (const [k, v] of rows) {
    const tr = el('tr');
    tr.appendChild(el('th', k)); tr.appendChild(el('td', v)); t.appendChild(tr);
  }
  info.appendChild(t);
  const scores = $('scores'); scores.replaceChildren();
  const list = (c.summary && Array.isArray(c.summary.scores)) ? c.summary.scores : [];
  if (list.length === 0) {
    scores.appendChild(el('tr')).appendChild(el('td', 'no thresholded scores'));
  }
  else {
    const h = el('tr');
    for (const k of ['score', 'value', 'flag at', 'reject at']) h.appendChild(el('th', k));
    scores.appendChild(h);
  }
  for (const s of list) {
    const tr = el('tr');
    const over = (thr) => thr != null && (s.rejects === 'below' ? s.value < thr : s.value > thr);
    if (over(s.reject)) tr.className = 'over-reject';
    else if (over(s.flag)) tr.className = 'over-flag';
    tr.appendChild(el('td', s.name));
    tr.appendChild(el('td', fmt(s.value), 'num'));
    const arrow = s.rejects === 'below' ? '< ' : '> ';
    tr.appendChild(el('td', s.flag != null ? arrow + fmt(s.flag) : '—', 'num'));
    tr.appendChild(el('td', s.reject != null ? arrow + fmt(s.reject) : '—', 'num'));
    scores.appendChild(tr);
  }
  const summary = Object.assign({}, c.summary || {}); delete summary.scores;
  $('summary').textContent = JSON.stringify(summary, null, 1);
  renderStages(c);
}

// One row per finished stage: its verdict and its scores, value / reject at.
function renderStages(c) {
  const t = $('stages'); t.replaceChildren();
  for (const s of c.stages || []) {
    const tr = el('tr');
    if (s.stage === c.stage) tr.className = 'current';
    tr.appendChild(el('th', s.stage));
    tr.appendChild(el('td', s.verdict + (s.reason ? ' ' + s.reason : ''), 'verdict-' + s.verdict));
    tr.appendChild(el('td', s.scores.map((x) => x.name + ' ' + fmt(x.value) +
        (x.reject != null ? ' / ' + fmt(x.reject) : '')).join(', ')));
    t.appendChild(tr);
  }
}

function frameCount(c) {
  if (c.frame_count) return c.frame_count;
  return video.duration && c.fps ? Math.round(video.duration * c.fps) : 0;
}

function renderTimeline() {
  const c = state.clip, tl = $('timeline'); tl.replaceChildren();
  const n = frameCount(c); if (!n) return;
  const pct = (f) => (100 * f / n) + '%';
  const trim = c.trim || { start_frame: c.start_frame, end_frame: c.end_frame };
  if (trim && trim.start_frame != null) {
    const d = el('div', undefined, 'trim');
    d.style.left = pct(trim.start_frame);
    d.style.width = pct((trim.end_frame != null ? trim.end_frame + 1 : n) - trim.start_frame);
    tl.appendChild(d);
  }
  for (const b of c.cuts) {
    const d = el('div', undefined, 'cut'); d.style.left = pct(b); tl.appendChild(d);
  }
  const head = el('div', undefined, 'head'); head.id = 'playhead'; tl.appendChild(head);
}

function currentFrame() {
  const fps = state.clip && state.clip.fps ? state.clip.fps : 30;
  return Math.floor(video.currentTime * fps + 1e-3);
}

function draw() {
  const c = state.clip; if (!c) return;
  const w = video.clientWidth, h = video.clientHeight;
  if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
  ctx.clearRect(0, 0, w, h);
  const vw = video.videoWidth || c.width, vh = video.videoHeight || c.height;
  const frame = currentFrame();
  $('frame').textContent = 'frame ' + frame + '  t=' + video.currentTime.toFixed(2) + ' s';
  const n = frameCount(c), head = $('playhead');
  if (head && n) head.style.left = (100 * frame / n) + '%';
  if (!vw || !vh) return;
  const s = Math.min(w / vw, h / vh), ox = (w - vw * s) / 2, oy = (h - vh * s) / 2;
  let boxes = state.byFrame.get(frame);
  for (let back = 1; !boxes && back <= Math.max(1, Math.round((c.fps || 30) / 2)); ++back) {
    boxes = state.byFrame.get(frame - back);
  }
  ctx.lineWidth = 2; ctx.font = '12px system-ui';
  for (const d of boxes || []) {
    const color = d.kind === 'hand' ? (d.hand_side === 0 ? '#4fc3f7' : '#81c784') : '#ffb74d';
    ctx.strokeStyle = color; ctx.fillStyle = color;
    const x = ox + d.x1 * s, y = oy + d.y1 * s;
    ctx.strokeRect(x, y, (d.x2 - d.x1) * s, (d.y2 - d.y1) * s);
    const contact = d.kind === 'hand' && d.contact_state >= 0 ? 'NSOPF'[d.contact_state] : '';
    const label = d.kind + (contact ? ' ' + contact : '');
    ctx.fillText(label, x + 2, Math.max(12, y - 3));
    if (d.kind === 'hand' && d.magnitude > 0) {
      // 100DOH offset: from the hand's centre towards the touched object.
      const cx = ox + (d.x1 + d.x2) / 2 * s, cy = oy + (d.y1 + d.y2) / 2 * s;
      const tx = cx + d.dx * d.magnitude * s, ty = cy + d.dy * d.magnitude * s;
      ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(tx, ty); ctx.stroke();
      ctx.beginPath(); ctx.arc(tx, ty, 3, 0, 2 * Math.PI); ctx.fill();
    }
  }
  if (c.cuts.includes(frame)) {
    ctx.strokeStyle = '#ff5d5d'; ctx.lineWidth = 6; ctx.strokeRect(3, 3, w - 6, h - 6);
  }
}

function tick() { draw(); if (!video.paused) requestAnimationFrame(tick); }

async function show(i) {
  if (state.queue.length === 0) { state.clip = null; renderQueue(); return; }
  state.index = Math.max(0, Math.min(i, state.queue.length - 1));
  renderQueue();
  const q = state.queue[state.index];
  // Keys can outrun the server: only the latest request may show its clip.
  const seq = ++state.seq;
  const c = await api('/api/clip/' + q.clip_id + '?stage=' + encodeURIComponent(q.stage));
  if (seq !== state.seq) return;
  state.clip = c;
  state.byFrame = new Map();
  for (const d of c.detections) {
    if (!state.byFrame.has(d.frame)) state.byFrame.set(d.frame, []);
    state.byFrame.get(d.frame).push(d);
  }
  document.body.dataset.clipId = c.clip_id;
  $('reason').value = reasonForStage[c.stage] || 'other';
  $('note').value = '';
  renderPanel(c);
  video.src = c.video_url;
  renderTimeline();
}

video.addEventListener('loadedmetadata', () => {
  if (!state.clip) return;
  video.currentTime = state.clip.start_s || 0;
  renderTimeline(); draw();
});
video.addEventListener('timeupdate', () => {
  const c = state.clip;
  if (c && c.end_s != null && video.currentTime > c.end_s + 1e-3) video.currentTime = c.start_s;
  draw();
});
video.addEventListener('seeked', draw);
video.addEventListener('play', tick);
window.addEventListener('resize', draw);

function togglePlay() { if (video.paused) video.play().catch(() => {}); else video.pause(); }
function step(frames) {
  video.pause();
  const fps = state.clip && state.clip.fps ? state.clip.fps : 30;
  video.currentTime = Math.max(0, video.currentTime + frames / fps);
}

async function decide(accept) {
  const c = state.clip, q = state.queue[state.index];
  if (!c || state.busy) return;
  // The clip on screen must be the one selected in the queue.
  if (!q || q.clip_id !== c.clip_id || q.stage !== c.stage) {
    toast('Still loading the clip');
    return;
  }
  const reviewer = $('reviewer').value.trim();
  if (!reviewer) { toast('Enter your name as reviewer first'); $('reviewer').focus(); return; }
  const code = $('reason').value;
  if (!accept && !code) { toast('Pick a reason to reject'); $('reason').focus(); return; }
  state.busy = true;
  try {
    await api('/api/decision', { clip_id: c.clip_id, stage: c.stage,
      decision: accept ? 'accept' : 'reject',
      reason_code: accept && code !== 'false_flag' ? '' : code,
      reason_text: $('note').value.trim(), reviewer });
    state.decisions += 1;
    document.body.dataset.decisions = state.decisions;
    toast((accept ? 'Accepted' : 'Rejected') + ' clip #' + c.clip_id);
    const at = state.queue.findIndex((x) => x.clip_id === c.clip_id && x.stage === c.stage);
    if (at >= 0) state.queue.splice(at, 1);
    await show(state.index);
  } catch (e) {
    toast('Not saved: ' + e.message);
  } finally {
    state.busy = false;
  }
}

$('reviewer').value = cfg.reviewer || localStorage.getItem('doasido.reviewer') || '';
$('reviewer').addEventListener('change', () =>
    localStorage.setItem('doasido.reviewer', $('reviewer').value.trim()));
$('accept').addEventListener('click', () => decide(true));
$('reject').addEventListener('click', () => decide(false));
$('next').addEventListener('click', () => show(state.index + 1));
$('prev').addEventListener('click', () => show(state.index - 1));
$('play').addEventListener('click', togglePlay);

document.addEventListener('keydown', (e) => {
  const tag = e.target.tagName;
  if (tag === 'INPUT' || tag === 'TEXTAREA' || tag === 'SELECT') {
    if (e.key === 'Escape') e.target.blur();
    return;
  }
  if (e.ctrlKey || e.metaKey || e.altKey) return;
  const reasons = $('reason').options;
  if (/^[1-9]$/.test(e.key) && Number(e.key) < reasons.length) {
    $('reason').selectedIndex = Number(e.key); e.preventDefault(); return;
  }
  switch (e.key) {
    case 'a': decide(true); break;
    case 'r': decide(false); break;
    case 'j': case 'ArrowDown': show(state.index + 1); break;
    case 'k': case 'ArrowUp': show(state.index - 1); break;
    case ' ': togglePlay(); break;
    case 'ArrowLeft': step(-1); break;
    case 'ArrowRight': step(1); break;
    case 'g': reloadQueue(); break;
    default: return;
  }
  e.preventDefault();
});

// Fetches the queue again (workers may have flagged more clips), keeping
// the current clip selected when it is still waiting.
async function reloadQueue() {
  const r = await api('/api/queue');
  const c = state.clip;
  state.queue = r.items;
  const at = c ? state.queue.findIndex((x) => x.clip_id === c.clip_id && x.stage === c.stage) : -1;
  await show(at >= 0 ? at : 0);
}
$('reload').addEventListener('click', () => reloadQueue().catch((e) => toast(e.message)));

reloadQueue().then(() => {
  state.ready = true;
  document.body.dataset.ready = '1';
}).catch((e) => toast('Cannot load the queue: ' + e.message));
)js";

}  // namespace

std::vector<ReasonChoice> ReviewOnlyReasons() {
  return {{kReasonPoorQuality, "poor video quality"},
          {kReasonFalseFlag, "flag was wrong (clip is fine)"},
          {kReasonOther, "other"}};
}

std::string ReviewPage(const std::string& nonce, const Json& config,
                       const std::vector<ReasonChoice>& stage_reasons) {
  // The reason list comes from the stages' own codes, so a renamed reason
  // cannot leave a stale choice on the page.
  std::string options;
  std::vector<ReasonChoice> reasons = stage_reasons;
  for (auto& r : ReviewOnlyReasons()) reasons.push_back(std::move(r));
  for (const auto& r : reasons) {
    options += "          <option value=\"" + HtmlEscape(r.code) + "\">" + HtmlEscape(r.label) +
               "</option>\n";
  }
  std::string body = kBody;
  const std::string marker = "@REASONS@";
  body.replace(body.find(marker), marker.size(), options);
  return ScriptedPage("doasido review", nonce, std::string(kDecisionPageStyle) + kStyle, body,
                      config, kScript);
}

}  // namespace doasido::review
