// The preference-study pages: one rater's trials and the results.
#include <cmath>
#include <cstdio>

#include "review/pages.h"

namespace doasido::review {
namespace {

const char* kStyle = R"css(
* { box-sizing: border-box; }
body { margin: 0; font: 15px/1.45 system-ui, sans-serif; background: #15171c; color: #e4e6eb; }
header { display: flex; gap: 16px; align-items: center; padding: 8px 16px; background: #1f232b;
         border-bottom: 1px solid #333a45; }
header h1 { font-size: 16px; margin: 0; } header .grow { flex: 1; }
a { color: #9fb7e0; }
main { padding: 12px 16px; }
.question { font-size: 17px; margin: 4px 0 12px; }
.row { display: grid; grid-template-columns: repeat(3, 1fr); gap: 12px; }
figure { margin: 0; background: #1f232b; border: 1px solid #333a45; border-radius: 6px;
         padding: 6px; }
figure video { width: 100%; display: block; background: #000; }
figcaption { text-align: center; padding: 4px; color: #9aa3b2; }
.choices { display: flex; gap: 12px; justify-content: center; margin-top: 14px; }
button { font: inherit; color: inherit; background: #262b35; border: 1px solid #3b4350;
         border-radius: 6px; padding: 10px 18px; cursor: pointer; }
button:hover { border-color: #6d8fd0; }
kbd { background: #333a45; border-radius: 3px; padding: 0 5px; font-size: 13px; }
input { font: inherit; color: inherit; background: #262b35; border: 1px solid #3b4350;
        border-radius: 4px; padding: 6px 8px; }
.hidden { display: none !important; }
.done { padding: 40px; text-align: center; font-size: 18px; }
.help { color: #9aa3b2; margin-top: 14px; text-align: center; }
table { border-collapse: collapse; margin: 10px 0 18px; }
td, th { padding: 4px 10px; border-bottom: 1px solid #2c313b; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.note { color: #ffd27a; }
)css";

const char* kBody = R"html(
<header><h1>doasido preference study</h1><span id="study"></span><span class="grow"></span>
  <span id="progress"></span><span id="who"></span></header>
<main>
  <form id="login" class="hidden">
    <p>Enter your rater name to start.</p>
    <input id="rater" autocomplete="off" required> <button type="submit">Start</button>
  </form>
  <div id="trial" class="hidden">
    <p class="question">Which rendering follows the object's true motion in the source video
      more consistently?</p>
    <div class="row">
      <figure><video id="left" muted playsinline loop preload="auto"></video>
        <figcaption>Left <kbd>1</kbd> / <kbd>←</kbd></figcaption></figure>
      <figure><video id="source" muted playsinline loop preload="auto"></video>
        <figcaption>Source video</figcaption></figure>
      <figure><video id="right" muted playsinline loop preload="auto"></video>
        <figcaption>Right <kbd>2</kbd> / <kbd>→</kbd></figcaption></figure>
    </div>
    <div class="choices">
      <button id="choose-left">Left is better <kbd>1</kbd></button>
      <button id="choose-tie">About the same <kbd>3</kbd></button>
      <button id="choose-right">Right is better <kbd>2</kbd></button>
    </div>
    <p class="help"><kbd>1</kbd>/<kbd>←</kbd> left · <kbd>2</kbd>/<kbd>→</kbd> right ·
      <kbd>3</kbd>/<kbd>↓</kbd> tie · <kbd>space</kbd> play/pause all ·
      <kbd>0</kbd> restart all</p>
  </div>
  <div id="finished" class="done hidden">All trials for you are done. Thank you!
    <p><a id="summary-link" href="#">Results so far</a></p></div>
</main>
)html";

const char* kScript = R"js(
'use strict';
const cfg = JSON.parse(document.getElementById('cfg').textContent);
const $ = (id) => document.getElementById(id);
const videos = ['left', 'source', 'right'].map($);
const state = { trial: null, busy: false, answered: 0, done: false };
window.doasidoState = state;
const base = '/api/study/' + encodeURIComponent(cfg.study);


function playAll() {
  for (const v of videos) { v.currentTime = 0; v.play().catch(() => {}); }
}

async function load() {
  const r = await api(base + '/next?rater=' + encodeURIComponent(cfg.rater));
  $('progress').textContent = r.rated + ' rated';
  if (r.done) {
    state.trial = null; state.done = true;
    $('trial').classList.add('hidden'); $('finished').classList.remove('hidden');
    document.body.dataset.done = '1';
    return;
  }
  state.trial = r;
  $('left').src = r.left_url; $('source').src = r.source_url; $('right').src = r.right_url;
  document.body.dataset.trial = r.trial_id;
  document.body.dataset.item = r.item_id;
  $('trial').classList.remove('hidden');
  playAll();
}

async function choose(side) {
  if (!state.trial || state.busy) return;
  state.busy = true;
  let refused = '';
  try {
    await api(base + '/answer', { trial_id: state.trial.trial_id, rater: cfg.rater, choice: side });
    state.answered += 1;
    document.body.dataset.answered = state.answered;
  } catch (e) {
    // Refused (e.g. the item filled up meanwhile): move on to a fresh trial.
    refused = e.message;
  }
  try {
    await load();
    if (refused) $('progress').textContent += ' (last answer not saved: ' + refused + ')';
  } finally { state.busy = false; }
}

$('study').textContent = cfg.study;
$('summary-link').href = '/study/' + encodeURIComponent(cfg.study) + '/summary';
if (!cfg.rater) {
  $('login').classList.remove('hidden');
  $('login').addEventListener('submit', (e) => {
    e.preventDefault();
    const name = $('rater').value.trim();
    if (name) location.search = '?rater=' + encodeURIComponent(name);
  });
} else {
  $('who').textContent = 'rater: ' + cfg.rater;
  $('choose-left').addEventListener('click', () => choose('left'));
  $('choose-right').addEventListener('click', () => choose('right'));
  $('choose-tie').addEventListener('click', () => choose('tie'));
  document.addEventListener('keydown', (e) => {
    if (e.target.tagName === 'INPUT' || e.ctrlKey || e.metaKey || e.altKey) return;
    switch (e.key) {
      case '1': case 'ArrowLeft': choose('left'); break;
      case '2': case 'ArrowRight': choose('right'); break;
      case '3': case 'ArrowDown': choose('tie'); break;
      case '0': playAll(); break;
      case ' ':
        if (videos[1].paused) videos.forEach((v) => v.play().catch(() => {}));
        else videos.forEach((v) => v.pause());
        break;
      default: return;
    }
    e.preventDefault();
  });
  load().then(() => { document.body.dataset.ready = '1'; });
}
)js";

std::string Fixed(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string Percent(double v) { return Fixed(100.0 * v, 1) + "%"; }

// One summary row whose value the tests and scripts read from data-value.
std::string Row(const std::string& id, const std::string& label, std::optional<double> value,
                const std::string& shown) {
  std::string data = value && std::isfinite(*value) ? Fixed(*value, 9) : "";
  return "<tr><th>" + HtmlEscape(label) + "</th><td class=\"num\" id=\"" + id +
         "\" data-value=\"" + data + "\">" + HtmlEscape(value ? shown : "n/a") + "</td></tr>\n";
}

std::string Join(const std::vector<std::string>& parts) {
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}

// Three stacked bars (A, tie, B) as inline SVG.
std::string ShareBar(const StudySummary& s) {
  const double w = 600;
  const double a = s.share_a * w, t = s.share_tie * w, b = s.share_b * w;
  std::string svg = "<svg id=\"share-chart\" width=\"600\" height=\"44\" viewBox=\"0 0 600 44\" "
                    "role=\"img\" aria-label=\"preference shares\">";
  svg += "<rect x=\"0\" y=\"0\" width=\"" + Fixed(a, 2) + "\" height=\"28\" fill=\"#2c9a58\"/>";
  svg += "<rect x=\"" + Fixed(a, 2) + "\" y=\"0\" width=\"" + Fixed(t, 2) +
         "\" height=\"28\" fill=\"#6b7280\"/>";
  svg += "<rect x=\"" + Fixed(a + t, 2) + "\" y=\"0\" width=\"" + Fixed(b, 2) +
         "\" height=\"28\" fill=\"#a8394a\"/>";
  svg += "<text x=\"2\" y=\"42\" fill=\"#e4e6eb\" font-size=\"12\">A " + Percent(s.share_a) +
         " · tie " + Percent(s.share_tie) + " · B " + Percent(s.share_b) + "</text></svg>";
  return svg;
}

}  // namespace

std::string StudyPage(const std::string& nonce, const Json& config) {
  return ScriptedPage("doasido study", nonce, kStyle, kBody, config, kScript);
}

std::string StudySummaryPage(const std::string& nonce, const StudySummary& s) {
  std::string html = std::string("<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                                 "\n<title>doasido study summary</title>\n<style nonce=\"") +
                     nonce + "\">" + kStyle + "</style></head>\n<body>\n";
  html += "<header><h1>Preference study: " + HtmlEscape(s.name) + "</h1></header>\n<main>\n";
  html += "<p>A = " + HtmlEscape(Join(s.a_labels)) + ", B = " + HtmlEscape(Join(s.b_labels)) +
          ". " + std::to_string(s.items) + " items, " + std::to_string(s.raters_per_item) +
          " raters per item; " + std::to_string(s.complete_items) + " items complete, " +
          std::to_string(s.ratings) + " ratings.</p>\n";
  html += ShareBar(s);
  html += "<table id=\"summary\">\n";
  html += Row("ratings", "ratings", s.ratings, std::to_string(s.ratings));
  html += Row("share-a", "A preferred", s.share_a, Percent(s.share_a));
  html += Row("share-b", "B preferred", s.share_b, Percent(s.share_b));
  html += Row("share-tie", "ties", s.share_tie, Percent(s.share_tie));
  html += Row("win-rate", "A's win rate among non-ties", s.win_rate_a,
              s.win_rate_a ? Percent(*s.win_rate_a) : "");
  html += Row("unanimous", "unanimous items (of complete)", s.unanimous_share,
              s.unanimous_share ? Percent(*s.unanimous_share) + " (" +
                                      std::to_string(s.unanimous_items) + ")"
                                : "");
  std::optional<double> kappa, p_bar, p_e;
  std::string note;
  if (s.kappa) {
    p_bar = s.kappa->P_bar;
    p_e = s.kappa->P_e;
    if (s.kappa->defined) kappa = s.kappa->kappa;
    note = s.kappa->note;
  }
  html += Row("kappa", "Fleiss' kappa (a / b / tie)", kappa, kappa ? Fixed(*kappa) : "");
  html += Row("p-bar", "observed agreement P̄", p_bar, p_bar ? Fixed(*p_bar) : "");
  html += Row("p-e", "chance agreement P_e", p_e, p_e ? Fixed(*p_e) : "");
  html += "</table>\n";
  if (!note.empty()) html += "<p class=\"note\" id=\"kappa-note\">" + HtmlEscape(note) + "</p>\n";
  html += "<table id=\"items\"><tr><th>item</th><th>A</th><th>B</th><th>tie</th>"
          "<th>complete</th><th>unanimous</th></tr>\n";
  for (const auto& row : s.per_item) {
    html += "<tr><td>" + HtmlEscape(row.item_id) + "</td><td class=\"num\">" +
            std::to_string(row.a) + "</td><td class=\"num\">" + std::to_string(row.b) +
            "</td><td class=\"num\">" + std::to_string(row.tie) + "</td><td>" +
            (row.complete ? "yes" : "no") + "</td><td>" + (row.unanimous ? "yes" : "") +
            "</td></tr>\n";
  }
  html += "</table>\n</main>\n</body></html>\n";
  return html;
}

}  // namespace doasido::review
