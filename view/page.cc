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
.done{color:#ccc}.marker{color:#1f4fa0}
#readings{display:flex;flex-wrap:wrap;gap:.3em 2em;margin:.2em 0 .5em}
.reading .name{font-size:.9em;color:#555}.reading .value{font-size:2.2em;font-weight:600;line-height:1.1}
.reading .age{font-size:.85em;color:#555}.reading .age.bad{color:#b00}
</style></head><body>
<header><h1 id="name">bosfuse live</h1><span>status: <b id="status">…</b></span>
<span id="link" class="warn">connecting…</span></header>
<main>
<section><h2>Thermocouples</h2>
<div id="readings"></div>
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
<div id="bos-state" class="small">…</div>
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
<script src="/snapshot.js"></script>
<script>
'use strict';
const $ = id => document.getElementById(id);
let run = null, chart = null, source = null, clockBasis = null, redrawPending = false;
let clock = null;               // {originMs, scale}: a t_s back to the time it was recorded
let runStatus = null, linkState = 'connecting…', runError = '';
let firstT = null, lastT = null;  // the run's time span so far (samples, BOS, markers)
const series = new Map();   // channel id -> dataset
const readings = new Map(); // channel id -> the current value's card
const devices = new Map();  // device id -> {row, state}
const bosSeries = new Map();  // channel id -> dataset of the live BOS temperature there
const bosFrames = new Set();  // frame ids shown (a reconnect sends the series again)
const alarms = new Map();     // "channel: kind" -> message, while active
const markers = [];           // the run's markers: {t, label}
let drawnMarkers = [];        // the marker lines the chart drew last: {label, x_px}
let latestBos = null, drawnBos = null, frameTimes = [], frames = {count: 0, t: null, rate: null}, bosState = null;
// Times to a hundredth of a second near the origin, coarser far from it, and
// never a signed zero ("−0.0 s" for an event 20 ms before t = 0).
function fmt(t) {
  const a = Math.abs(t), digits = a < 10 ? 2 : a < 1000 ? 1 : 0;
  let text = t.toFixed(digits);
  if (Number(text) === 0) text = (0).toFixed(digits);
  return text.replace('-', '−') + ' s';
}
// How long ago experiment second `t` was recorded, by the page's clock.
function ago(t) {
  if (!clock) return '';
  const s = Math.max(0, (Date.now() - (clock.originMs + t / clock.scale * 1000)) / 1000);
  return s < 90 ? s.toFixed(0) + ' s ago' : s < 5400 ? (s / 60).toFixed(0) + ' min ago' : (s / 3600).toFixed(1) + ' h ago';
}
function spanTo(t) {
  if (firstT === null || t < firstT) firstT = t;
  if (lastT === null || t > lastT) lastT = t;
}
function element(tag, className, text) {
  const e = document.createElement(tag); e.className = className; e.textContent = text; return e;
}
function showRunError(message) { runError = message; showLink(); }
// A finished run is not "live": its status says so in grey, whatever the stream does.
function showLink() {
  const finished = runStatus !== null && runStatus !== 'running';
  const [text, kind] = runError ? [runError, 'bad'] : finished ? ['finished: the run is ' + runStatus, 'done']
                     : [linkState, linkState === 'live' ? 'ok' : 'warn'];
  $('link').textContent = text; $('link').className = kind;
  showBosState();
}
function onStatus(s) { runStatus = s.status; $('status').textContent = s.status; showLink(); }
function applyRun(body) {
  run = body;
  $('name').textContent = run.name;
  if (runStatus === null) onStatus({status: run.status});
  for (const d of run.devices) deviceRow(d.id, d.name, d.kind);
  for (const c of run.channels) if (c.kind === 'thermocouple' && !series.has(c.id)) addSeries(c);
  showLimits();
}
async function loadRun() {
  const reply = await fetch('/api/run'), body = await reply.json();
  if (!reply.ok) { showRunError(body.error); throw new Error(body.error); }
  applyRun(body);
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
  addReading(c, ds.borderColor);
}
// The channel's current value in large type with its unit and age, as a
// logger's main view shows it.
function addReading(c, colour) {
  const box = element('div', 'reading', ''), name = element('div', 'name', c.name);
  const value = element('div', 'value', '—'), age = element('div', 'age', 'no value yet');
  name.style.borderLeft = '4px solid ' + colour; name.style.paddingLeft = '.3em';
  box.dataset.channel = c.name; box.append(name, value, age); $('readings').append(box);
  readings.set(c.id, {value, age, unit: unitText(c.unit), decimals: c.decimals, last: null, lastOk: null});
}
// A value at its channel's digits (storage/value_digits.h): its resolution's
// decimals, or 6 significant digits where the resolution is unknown.
function valueText(v, decimals) {
  return decimals === null || decimals === undefined ? String(Number(v.toPrecision(6))) : v.toFixed(decimals);
}
function showReading(r) {
  if (!r.last) return;
  if (r.last.status === 'ok') {
    r.value.textContent = valueText(r.last.value, r.decimals) + ' ' + r.unit; r.age.textContent = ago(r.last.t); r.age.className = 'age';
    return;
  }
  r.value.textContent = '—';
  r.age.textContent = r.last.status + ' ' + ago(r.last.t) +
    (r.lastOk ? '; last value ' + valueText(r.lastOk.value, r.decimals) + ' ' + r.unit + ' ' + ago(r.lastOk.t) : '');
  r.age.className = 'age bad';
}
function deviceRow(id, name, kind) {
  if (devices.has(id)) return devices.get(id);
  const tr = document.createElement('tr'), a = document.createElement('td'), b = document.createElement('td'),
        c = document.createElement('td');
  a.textContent = name; b.textContent = 'ok'; b.className = 'ok';
  tr.append(a, b, c); $('devices').append(tr);
  const d = {cell: b, counts: c, camera: kind === 'camera', ok: 0, failed: 0, skipped: 0, pollT: null, pollFailed: false,
             lastOkT: null};
  devices.set(id, d); showCounts(d); return d;
}
// A module: polls that gave every channel a value or at least one a failure
// status (a poll's samples share its time stamp), polls the logger skipped
// (its "skipped" events), and how long ago it last gave a value. A camera:
// its frames, their rate and the age of the last.
function showCounts(d) {
  if (d.camera) {
    d.counts.textContent = frames.count === 0 ? 'no frames yet'
      : 'frames ' + frames.count + (frames.rate === null ? '' : ', ' + frames.rate.toFixed(2) + ' per s') +
        ', last ' + ago(frames.t);
    return;
  }
  const age = d.lastOkT === null ? 'no value yet' : 'last value ' + ago(d.lastOkT);
  d.counts.textContent = 'polls ok ' + d.ok + ', failed ' + d.failed + ', skipped ' + d.skipped + '; ' + age;
}
function countReading(s) {
  const c = run.channels.find(x => x.id === s.channel);
  if (!c) return;
  const d = deviceRow(c.device_id, c.device);
  const bad = s.status !== 'ok';
  if (d.pollT !== s.t_s) { d.pollT = s.t_s; d.pollFailed = bad; bad ? d.failed++ : d.ok++; }
  else if (bad && !d.pollFailed) { d.pollFailed = true; d.ok--; d.failed++; }
  if (!bad) d.lastOkT = s.t_s;
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
// An event's colour says what it means: trouble red, recovery green, lost
// polls amber, markers blue, the rest plain.
const eventColours = {alarm: 'bad', error: 'bad', disconnect: 'bad', interrupted: 'bad', 'alarm-cleared': 'ok',
                      reconnect: 'ok', connect: 'ok', skipped: 'warn', gap: 'warn', marker: 'marker'};
function onEvent(e) {
  const li = document.createElement('li');
  li.textContent = fmt(e.t_s) + ' ' + e.kind + (e.device ? ' [' + e.device + ']' : '') + ': ' + e.message;
  li.className = eventColours[e.kind] || '';
  if (e.kind === 'alarm' || e.kind === 'alarm-cleared') onAlarm(e);
  if (e.kind === 'marker') { markers.push({t: e.t_s, label: e.message}); spanTo(e.t_s); scheduleRedraw(); }
  $('events').prepend(li);
  if (e.device_id === undefined) return;
  if (e.kind === 'skipped') { const d = deviceRow(e.device_id, e.device); d.skipped += parseInt(e.message, 10) || 0; showCounts(d); }
  const d = deviceRow(e.device_id, e.device || ('device ' + e.device_id));
  if (e.kind === 'disconnect') { d.cell.textContent = 'disconnected since ' + fmt(e.t_s); d.cell.className = 'bad'; }
  else if (e.kind === 'reconnect') { d.cell.textContent = 'reconnected at ' + fmt(e.t_s); d.cell.className = 'ok'; }
  else if (e.kind === 'connect') { d.cell.textContent = 'ok'; d.cell.className = 'ok'; }
}
function onSample(s) {
  spanTo(s.t_s);
  countReading(s);
  const ds = series.get(s.channel);
  if (!ds) { if (!run.channels.some(c => c.id === s.channel)) loadRun(); return; }
  ds.data.push({x: s.t_s, y: s.status === 'ok' ? s.value : null});
  const r = readings.get(s.channel), reading = {status: s.status, value: s.value, t: s.t_s};
  r.last = reading; if (s.status === 'ok') r.lastOk = reading;
  showReading(r);
  scheduleRedraw();
}
function onFrames(f) {
  $('frame-count').textContent = f.count; $('frame-time').textContent = fmt(f.last_t_s);
  frameTimes.push({n: f.count, t: f.last_t_s}); frameTimes = frameTimes.slice(-10);
  const first = frameTimes[0];
  // Over the last ten batches while they come, else over the whole run (a finished one comes in one batch).
  const rate = f.last_t_s > first.t ? (f.count - first.n) / (f.last_t_s - first.t)
             : f.count > 1 && f.last_t_s > f.first_t_s ? (f.count - 1) / (f.last_t_s - f.first_t_s) : null;
  frames = {count: f.count, t: f.last_t_s, rate};
  if (frames.rate !== null) $('frame-rate').textContent = frames.rate.toFixed(2) + ' per s';
  for (const d of devices.values()) if (d.camera) showCounts(d);
  showBosState();
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
  spanTo(b.t_s);
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
function onBosState(s) { bosState = s; showBosState(); }
// A finished run without frames says so, rather than waiting for frames that will not come.
function showBosState() {
  const s = bosState;
  if (!s) return;
  const finished = runStatus !== null && runStatus !== 'running';
  const state = finished && frames.count === 0 ? 'the run has no frames' : s.state;
  $('bos-state').textContent = state + (s.temperature_source ? '; temperatures from ' + s.temperature_source : '') +
    '; frames evaluated ' + s.evaluated + ', skipped ' + s.skipped +
    (latestBos ? '; last took ' + (latestBos.decode_ms + latestBos.evaluate_ms).toFixed(0) + ' ms' : '');
}
// The run's markers as dashed vertical lines with their label, drawn over the curves.
const markerLines = {id: 'markerLines', afterDatasetsDraw(c) {
  const x = c.scales.x, area = c.chartArea, g = c.ctx, drawn = [];
  g.save(); g.strokeStyle = g.fillStyle = '#1f4fa0'; g.setLineDash([5, 4]); g.lineWidth = 1.5; g.font = '12px sans-serif';
  markers.forEach((m, i) => {
    const px = x.getPixelForValue(m.t);
    if (!(px >= area.left - 0.5 && px <= area.right + 0.5)) return;
    g.beginPath(); g.moveTo(px, area.top); g.lineTo(px, area.bottom); g.stroke();
    g.fillText(m.label, px + 4, area.top + 14 + 14 * (i % 3));
    drawn.push({label: m.label, x_px: px});
  });
  g.restore();
  drawnMarkers = drawn;
}};
// The window counts back from the newest time but never past the run's
// first, which may lie before t = 0 (the origin is a marker made later).
function redraw() {
  const w = Number($('window').value);
  const x = chart.options.scales.x, span = firstT !== null && lastT > firstT;
  x.min = span ? (w > 0 ? Math.max(lastT - w, firstT) : firstT) : undefined;
  x.max = span ? lastT : undefined;
  chart.update('none');
  if (latestBos && latestBos !== drawnBos) { drawnBos = latestBos; showBos(latestBos); }
}
function scheduleRedraw() {
  if (redrawPending) return;
  redrawPending = true;
  setTimeout(() => { redrawPending = false; redraw(); }, 250);
}
function onClock(c) {
  if (clockBasis !== null && clockBasis !== c.basis) { restart(); return; }
  clockBasis = c.basis;
  clock = {originMs: Date.parse(c.origin_utc), scale: c.time_scale || 1};
  $('basis').textContent = 't: ' + c.basis; $('note').textContent = c.note;
  chart.options.scales.x.title.text = 'experiment time / s since ' + c.origin;
}
function onRunError(e) { runError = e.error; showLink(); }
const handlers = {clock: onClock, status: onStatus, event: onEvent, sample: onSample, frames: onFrames, bos: onBos,
                  'bos-state': onBosState, 'run-error': onRunError};
// Server-Sent Events text as the stream sends it (the snapshot's), through the same handlers.
function feed(text) {
  for (const block of text.split('\n\n')) {
    let type = null, data = null;
    for (const line of block.split('\n')) {
      if (line.startsWith('event: ')) type = line.slice(7); else if (line.startsWith('data: ')) data = line.slice(6);
    }
    if (type !== null && data !== null && handlers[type]) handlers[type](JSON.parse(data));
  }
}
// The stream goes on after `after`, the snapshot's cursor (after a
// reconnect the browser's Last-Event-ID says where).
function connect(after) {
  source = new EventSource('/events' + (after ? '?after=' + encodeURIComponent(after) : ''));
  source.onopen = () => { linkState = 'live'; showLink(); };
  source.onerror = () => { linkState = 'reconnecting…'; showLink(); };
  for (const [type, handle] of Object.entries(handlers)) source.addEventListener(type, m => handle(JSON.parse(m.data)));
}
// A new time origin moves every point: start again from the run's beginning.
function restart() {
  source.close(); clockBasis = null; firstT = lastT = null; markers.length = 0;
  for (const ds of series.values()) ds.data = [];
  for (const ds of bosSeries.values()) ds.data = [];
  for (const r of readings.values()) { r.last = r.lastOk = null; }
  bosFrames.clear(); latestBos = drawnBos = null; frameTimes = []; alarms.clear(); frames = {count: 0, t: null, rate: null};
  for (const d of devices.values()) { d.ok = 0; d.failed = 0; d.skipped = 0; d.pollT = null; d.lastOkT = null; }
  $('events').replaceChildren();
  connect();
}
function tick() {
  for (const d of devices.values()) showCounts(d);
  for (const r of readings.values()) showReading(r);
}
// The first paint already holds the run as it stands (the snapshot script
// loaded before this one), drawn at once without animation; the stream then
// adds what comes after.
function start() {
  if (typeof Chart === 'undefined') { showRunError('Chart.js did not load'); return; }
  chart = new Chart($('chart'), {type: 'line', data: {datasets: []}, plugins: [markerLines],
    options: {animation: false, responsive: true, maintainAspectRatio: false, normalized: true,
      // The window's bounds are exact times (the run's first sample, say): no tick of their own at 484.06.
      scales: {x: {type: 'linear', ticks: {includeBounds: false}, title: {display: true, text: 'experiment time / s'}},
               y: {title: {display: true, text: '°C'}}},
      plugins: {decimation: {enabled: true, algorithm: 'lttb', samples: 1000}}}});
  $('window').onchange = redraw;
  setInterval(tick, 1000);
  const snapshot = window.bosfuseSnapshot;
  if (!snapshot || snapshot.error) {
    if (snapshot) showRunError(snapshot.error);
    loadRun().then(() => connect(), () => {});
    return;
  }
  applyRun(snapshot.run);
  feed(snapshot.stream);
  redraw();
  connect(snapshot.cursor);
}
start();
</script></body></html>
)html";

}  // namespace

std::string_view live_page_html() { return kPage; }

}  // namespace bosfuse::view
