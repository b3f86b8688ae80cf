#include "view/page.h"

namespace bosfuse::view {
namespace {

// Kept as one raw string so the page is a single response with nothing to
// find on disk. Data from the run reaches the DOM only through textContent.
constexpr std::string_view kPage = R"html(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>bosfuse live</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{font-family:system-ui,sans-serif;margin:0;background:#fafafa;color:#222}
header{padding:.5em 1em;background:#234;color:#fff;display:flex;gap:1.5em;align-items:baseline;flex-wrap:wrap}
header h1{font-size:1.2em;margin:0}
main{display:grid;grid-template-columns:minmax(0,3fr) minmax(16em,1fr);gap:1em;padding:1em}
section{background:#fff;border:1px solid #ddd;border-radius:4px;padding:.5em 1em}
h2{font-size:1em;margin:.3em 0}
#chart-box{position:relative;height:60vh}
.ok{color:#070}.bad{color:#b00}.warn{color:#a60}
#events{max-height:40vh;overflow:auto;font-size:.9em;margin:0;padding-left:1.2em}
#basis,#note{font-size:.85em;color:#555}
table{border-collapse:collapse;font-size:.9em}td,th{padding:.1em .5em;text-align:left}
#frame-view{max-width:100%;border:1px solid #ddd;display:block;margin:.3em 0}
.small{font-size:.85em;color:#555}
#alarms li{color:#b00}
</style></head><body>
<header><h1 id="name">bosfuse live</h1><span>status: <b id="status">…</b></span>
<span id="link" class="warn">connecting…</span></header>
<main>
<section><h2>Thermocouples</h2>
<label>window <select id="window"><option value="60">last 1 min</option><option value="300">last 5 min</option>
<option value="1800" selected>last 30 min</option><option value="0">whole run</option></select></label>
<div id="chart-box"><canvas id="chart"></canvas></div>
<div id="basis"></div><div id="note" class="warn"></div></section>
<div>
<section><h2>Alarms</h2><ul id="alarms"></ul><div id="limits" class="small"></div></section>
<section><h2>Devices</h2><table id="devices"></table></section>
<section><h2>Frames</h2><div>count <b id="frame-count">0</b>, <span id="frame-rate">–</span>, last at <b id="frame-time">–</b></div></section>
<section><h2>Events</h2><ol id="events"></ol></section>
</div>
<section><h2>Live BOS at the thermocouples</h2>
<div id="bos-state" class="small">waiting for frames</div>
<table id="bos-table"><thead><tr><th>probe</th><th>|d| / px</th><th>u / px</th><th>v / px</th><th>BOS temperature</th>
<th>thermocouple / °C</th></tr></thead><tbody id="bos-rows"></tbody></table>
<div class="small">BOS temperatures are drawn dashed on the chart, with the thermocouple they sit at. They are the
viewer's own quick evaluation (probe mode, newest frame first); <code>bosfuse process</code> makes the stored ones.</div>
</section>
<section><h2>Latest frame</h2>
<canvas id="frame-view" width="320" height="240"></canvas>
<div class="small">Circles: displacement magnitude at each probe (area grows with |d|), arrows its direction, magnified.</div>
<h2>Image quality against the reference frame</h2>
<div>Q<sub>L</sub> <b id="q-l">–</b>, Q<sub>C</sub> <b id="q-c">–</b>, Q<sub>mod</sub> <b id="q-mod">–</b>
<span id="q-verdict"></span></div>
<div class="small">Q<sub>mod</sub> = Q<sub>L</sub>·Q<sub>C</sub> compares this frame's brightness (Q<sub>L</sub>) and contrast
(Q<sub>C</sub>) with the reference frame's (Gojani &amp; Obayashi 2012): cross-correlation worked at 0.70 (Pentax K-5),
was usable at 0.33 (Shimadzu HPV-1) and failed at 0.01 (Imacon DSR200). Here: good from 0.6, usable from 0.3, poor below.
A fall during a run means focus, exposure or lighting changed.</div>
</section></main>
<script src="/chart.js"></script>
<script>
'use strict';
const $ = id => document.getElementById(id);
let run = null, chart = null, source = null, clockBasis = null, lastT = 0, redrawPending = false;
const series = new Map();   // channel id -> dataset
const devices = new Map();  // device id -> {row, state}
const bosSeries = new Map();  // channel id -> dataset of the live BOS temperature there
const bosFrames = new Set();  // frame ids shown (a reconnect sends the series again)
const alarms = new Map();     // "channel: kind" -> message, while active
let latestBos = null, drawnBos = null, frameTimes = [];
const fmt = t => t.toFixed(1) + ' s';

function showRunError(message) { $('link').textContent = message; $('link').className = 'bad'; }
async function loadRun() {
  const reply = await fetch('/api/run'), body = await reply.json();
  if (!reply.ok) { showRunError(body.error); throw new Error(body.error); }
  run = body;
  $('name').textContent = run.name;
  $('status').textContent = run.status;
  for (const d of run.devices) deviceRow(d.id, d.name);
  for (const c of run.channels) if (c.kind === 'thermocouple' && !series.has(c.id)) addSeries(c);
  showLimits();
}
function unitText(u) { return u === 'degC' ? '°C' : u; }
function addSeries(c) {
  const hue = (series.size * 137) % 360;
  const ds = {label: c.name + ' (' + unitText(c.unit) + ')', data: [], borderColor: 'hsl(' + hue + ',70%,40%)', hue,
              pointRadius: 0, borderWidth: 1.5, parsing: false, spanGaps: false};
  series.set(c.id, ds);
  chart.data.datasets.push(ds);
  const units = new Set(run.channels.filter(x => series.has(x.id)).map(x => unitText(x.unit)));
  chart.options.scales.y.title.text = [...units].join(', ');
}
function deviceRow(id, name) {
  if (devices.has(id)) return devices.get(id);
  const tr = document.createElement('tr'), a = document.createElement('td'), b = document.createElement('td'),
        c = document.createElement('td');
  a.textContent = name; b.textContent = 'ok'; b.className = 'ok';
  tr.append(a, b, c); $('devices').append(tr);
  const d = {cell: b, counts: c, ok: 0, failed: 0, skipped: 0, pollT: null, pollFailed: false, lastOkMs: null};
  devices.set(id, d); return d;
}
// Polls that gave every channel a value or at least one a failure status
// (a poll's samples share its time stamp), polls the logger skipped (its
// "skipped" events), and how long ago the device last gave a value (wall
// clock of this page).
function showCounts(d) {
  const age = d.lastOkMs === null ? 'no value yet' : 'last value ' + ((Date.now() - d.lastOkMs) / 1000).toFixed(0) + ' s ago';
  d.counts.textContent = 'polls ok ' + d.ok + ', failed ' + d.failed + ', skipped ' + d.skipped + '; ' + age;
}
function countReading(s) {
  const c = run.channels.find(x => x.id === s.channel);
  if (!c) return;
  const d = deviceRow(c.device_id, c.device);
  const bad = s.status !== 'ok';
  if (d.pollT !== s.t_s) { d.pollT = s.t_s; d.pollFailed = bad; bad ? d.failed++ : d.ok++; }
  else if (bad && !d.pollFailed) { d.pollFailed = true; d.ok--; d.failed++; }
  if (!bad) d.lastOkMs = Date.now();
  showCounts(d);
}
function onAlarm(e) {
  const m = /^(.*?): (low|high|rate|stale)/.exec(e.message);
  if (!m) return;
  const key = m[1] + ': ' + m[2];
  if (e.kind === 'alarm') alarms.set(key, fmt(e.t_s) + ' ' + e.message); else alarms.delete(key);
  $('alarms').replaceChildren(...[...alarms.values()].map(t => { const li = document.createElement('li'); li.textContent = t; return li; }));
}
function showLimits() {
  const parts = [];
  for (const c of run.channels) {
    const a = c.alarms || {}, u = ' ' + unitText(c.unit), l = [];
    if (a.low !== undefined) l.push('low ' + a.low + u);
    if (a.high !== undefined) l.push('high ' + a.high + u);
    if (a.rate_per_min !== undefined) l.push('rate ' + a.rate_per_min + u + '/min');
    if (a.stale_s !== undefined) l.push('stale after ' + a.stale_s + ' s');
    if (l.length) parts.push(c.name + ': ' + l.join(', '));
  }
  $('limits').textContent = parts.length ? 'limits — ' + parts.join('; ') : 'no alarm limits in the experiment file';
}
function onEvent(e) {
  const li = document.createElement('li');
  li.textContent = fmt(e.t_s) + ' ' + e.kind + (e.device ? ' [' + e.device + ']' : '') + ': ' + e.message;
  if (e.kind.startsWith('alarm')) { li.className = 'bad'; onAlarm(e); }
  $('events').prepend(li);
  if (e.device_id === undefined) return;
  if (e.kind === 'skipped') { const d = deviceRow(e.device_id, e.device); d.skipped += parseInt(e.message, 10) || 0; showCounts(d); }
  const d = deviceRow(e.device_id, e.device || ('device ' + e.device_id));
  if (e.kind === 'disconnect') { d.cell.textContent = 'disconnected since ' + fmt(e.t_s); d.cell.className = 'bad'; }
  else if (e.kind === 'reconnect') { d.cell.textContent = 'reconnected at ' + fmt(e.t_s); d.cell.className = 'ok'; }
  else if (e.kind === 'connect') { d.cell.textContent = 'ok'; d.cell.className = 'ok'; }
}
function onSample(s) {
  if (s.t_s > lastT) lastT = s.t_s;
  countReading(s);
  const ds = series.get(s.channel);
  if (!ds) { if (!run.channels.some(c => c.id === s.channel)) loadRun(); return; }
  ds.data.push({x: s.t_s, y: s.status === 'ok' ? s.value : null});
  scheduleRedraw();
}
function bosDataset(p) {
  if (bosSeries.has(p.channel)) return bosSeries.get(p.channel);
  const tc = series.get(p.channel), hue = tc ? tc.hue : (bosSeries.size * 137 + 60) % 360;
  const ds = {label: 'BOS at ' + p.name + ' (°C)', data: [], borderColor: 'hsl(' + hue + ',70%,55%)',
              borderDash: [6, 3], pointRadius: 2, borderWidth: 1.5, parsing: false, spanGaps: false};
  bosSeries.set(p.channel, ds);
  chart.data.datasets.push(ds);
  return ds;
}
function onBos(b) {
  if (bosFrames.has(b.frame_id)) return;
  bosFrames.add(b.frame_id);
  for (const p of b.probes) bosDataset(p).data.push({x: b.t_s, y: p.t_c === undefined ? null : p.t_c});
  if (b.t_s > lastT) lastT = b.t_s;
  if (!latestBos || b.frame_id > latestBos.frame_id) latestBos = b;
  scheduleRedraw();
}
function lastValue(channel) {
  const ds = series.get(channel);
  for (let i = ds ? ds.data.length - 1 : -1; i >= 0; i--) if (ds.data[i].y !== null) return ds.data[i].y;
  return null;
}
function cell(text) { const td = document.createElement('td'); td.textContent = text; return td; }
const num = (v, digits) => v === undefined || v === null ? '—' : v.toFixed(digits);
// The BOS temperature with its standard uncertainties: random (the frame's
// noise), then systematic (the set-up's Type-B budget), when estimated.
const sig = v => v < 0.1 ? v.toPrecision(1) : v.toFixed(1);
function withSigma(p) {
  if (p.t_c === undefined || p.t_c === null) return '—';
  let text = p.t_c.toFixed(1);
  if (p.sigma_random_c !== undefined) text += ' ± ' + sig(p.sigma_random_c) + ' °C (random)';
  if (p.sigma_systematic_c !== undefined) text += ' ± ' + sig(p.sigma_systematic_c) + ' °C (systematic)';
  return text;
}
function showBos(b) {
  $('bos-rows').replaceChildren(...b.probes.map(p => {
    const tr = document.createElement('tr'), tc = lastValue(p.channel);
    tr.append(cell(p.name), cell(p.valid ? num(p.shift_px, 3) : 'invalid'), cell(num(p.u_px, 3)), cell(num(p.v_px, 3)),
              cell(withSigma(p)), cell(num(tc, 1)));
    return tr;
  }));
  const q = b.quality;
  $('q-l').textContent = num(q.q_l, 2); $('q-c').textContent = num(q.q_c, 2); $('q-mod').textContent = num(q.q_mod, 2);
  const v = q.q_mod === null ? ['', ''] : q.q_mod >= 0.6 ? ['good', 'ok'] : q.q_mod >= 0.3 ? ['usable', 'warn']
          : ['poor: expect cross-correlation to fail', 'bad'];
  $('q-verdict').textContent = v[0]; $('q-verdict').className = v[1];
  const img = new Image();
  img.onload = () => drawFrame(img, b);
  img.src = '/frame.png?frame=' + b.frame_id;
}
function drawFrame(img, b) {
  const canvas = $('frame-view'), g = canvas.getContext('2d');
  canvas.width = img.width; canvas.height = img.height;
  g.drawImage(img, 0, 0);
  const scale = img.width / b.width_px;
  const largest = Math.max(1e-9, ...b.probes.map(p => p.valid ? p.shift_px : 0));
  g.font = '12px sans-serif'; g.lineWidth = 2;
  for (const p of b.probes) {
    const x = p.x_px * scale, y = p.y_px * scale;
    g.strokeStyle = g.fillStyle = p.valid ? 'rgb(220,40,0)' : 'rgb(120,120,120)';
    const r = p.valid ? 4 + 16 * Math.sqrt(p.shift_px / largest) : 4;
    g.beginPath(); g.arc(x, y, r, 0, 2 * Math.PI); g.stroke();
    if (p.valid) {
      const k = 30 / largest;
      g.beginPath(); g.moveTo(x, y); g.lineTo(x + p.u_px * k, y + p.v_px * k); g.stroke();
    }
    g.fillText(p.name + (p.valid ? ' ' + p.shift_px.toFixed(3) + ' px' : ' invalid'), x + r + 3, y - 3);
  }
}
function onBosState(s) {
  $('bos-state').textContent = s.state + (s.temperature_source ? '; temperatures from ' + s.temperature_source : '') +
    '; frames evaluated ' + s.evaluated + ', skipped ' + s.skipped +
    (latestBos ? '; last took ' + (latestBos.decode_ms + latestBos.evaluate_ms).toFixed(0) + ' ms' : '');
}
function scheduleRedraw() {
  if (redrawPending) return;
  redrawPending = true;
  setTimeout(() => {
    redrawPending = false;
    const w = Number($('window').value);
    chart.options.scales.x.min = w > 0 ? Math.max(lastT - w, Math.min(0, lastT)) : undefined;
    chart.update('none');
    if (latestBos && latestBos !== drawnBos) { drawnBos = latestBos; showBos(latestBos); }
  }, 250);
}
function connect() {
  source = new EventSource('/events');
  source.onopen = () => { $('link').textContent = 'live'; $('link').className = 'ok'; };
  source.onerror = () => { $('link').textContent = 'reconnecting…'; $('link').className = 'warn'; };
  source.addEventListener('clock', m => {
    const c = JSON.parse(m.data);
    if (clockBasis !== null && clockBasis !== c.basis) { restart(); return; }
    clockBasis = c.basis;
    $('basis').textContent = 't: ' + c.basis; $('note').textContent = c.note;
    chart.options.scales.x.title.text = 'experiment time / s since ' + c.origin;
  });
  source.addEventListener('run-error', m => {
    const e = JSON.parse(m.data).error;
    e ? showRunError(e) : source.onopen();
  });
  source.addEventListener('status', m => { $('status').textContent = JSON.parse(m.data).status; });
  source.addEventListener('event', m => onEvent(JSON.parse(m.data)));
  source.addEventListener('sample', m => onSample(JSON.parse(m.data)));
  source.addEventListener('frames', m => {
    const f = JSON.parse(m.data);
    $('frame-count').textContent = f.count; $('frame-time').textContent = fmt(f.last_t_s);
    frameTimes.push({n: f.count, t: f.last_t_s}); frameTimes = frameTimes.slice(-10);
    const first = frameTimes[0];
    if (f.last_t_s > first.t) $('frame-rate').textContent = ((f.count - first.n) / (f.last_t_s - first.t)).toFixed(2) + ' per s';
  });
  source.addEventListener('bos', m => onBos(JSON.parse(m.data)));
  source.addEventListener('bos-state', m => onBosState(JSON.parse(m.data)));
}
// A new time origin moves every point: start again from the run's beginning.
function restart() {
  source.close(); clockBasis = null; lastT = 0;
  for (const ds of series.values()) ds.data = [];
  for (const ds of bosSeries.values()) ds.data = [];
  bosFrames.clear(); latestBos = drawnBos = null; frameTimes = []; alarms.clear();
  for (const d of devices.values()) { d.ok = 0; d.failed = 0; d.skipped = 0; d.pollT = null; d.lastOkMs = null; }
  $('events').replaceChildren();
  connect();
}
async function start() {
  if (typeof Chart === 'undefined') { $('link').textContent = 'Chart.js did not load'; return; }
  chart = new Chart($('chart'), {type: 'line', data: {datasets: []},
    options: {animation: false, responsive: true, maintainAspectRatio: false, normalized: true,
      scales: {x: {type: 'linear', title: {display: true, text: 'experiment time / s'}},
               y: {title: {display: true, text: '°C'}}},
      plugins: {decimation: {enabled: true, algorithm: 'lttb', samples: 1000}}}});
  $('window').onchange = scheduleRedraw;
  setInterval(() => { for (const d of devices.values()) showCounts(d); }, 1000);
  await loadRun();
  connect();
}
start();
</script></body></html>
)html";

}  // namespace

std::string_view live_page_html() { return kPage; }

}  // namespace bosfuse::view
