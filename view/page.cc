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
table{border-collapse:collapse;font-size:.9em}td{padding:.1em .5em}
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
<section><h2>Devices</h2><table id="devices"></table></section>
<section><h2>Frames</h2><div>count <b id="frame-count">0</b>, last at <b id="frame-time">–</b></div></section>
<section><h2>Events</h2><ol id="events"></ol></section>
</div></main>
<script src="/chart.js"></script>
<script>
'use strict';
const $ = id => document.getElementById(id);
let run = null, chart = null, source = null, clockBasis = null, lastT = 0, redrawPending = false;
const series = new Map();   // channel id -> dataset
const devices = new Map();  // device id -> {row, state}
const fmt = t => t.toFixed(1) + ' s';

async function loadRun() {
  run = await (await fetch('/api/run')).json();
  $('name').textContent = run.name;
  $('status').textContent = run.status;
  for (const d of run.devices) deviceRow(d.id, d.name);
  for (const c of run.channels) if (c.kind === 'thermocouple' && !series.has(c.id)) addSeries(c);
}
function unitText(u) { return u === 'degC' ? '°C' : u; }
function addSeries(c) {
  const hue = (series.size * 137) % 360;
  const ds = {label: c.name + ' (' + unitText(c.unit) + ')', data: [], borderColor: 'hsl(' + hue + ',70%,40%)',
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
  const d = {cell: b, counts: c, ok: 0, failed: 0, lastOkMs: null}; devices.set(id, d); return d;
}
// Readings (one per channel and poll) that gave a value or a failure status,
// and how long ago the device last gave a value (wall clock of this page).
function showCounts(d) {
  const age = d.lastOkMs === null ? 'no value yet' : 'last value ' + ((Date.now() - d.lastOkMs) / 1000).toFixed(0) + ' s ago';
  d.counts.textContent = 'readings ok ' + d.ok + ', failed ' + d.failed + '; ' + age;
}
function countReading(s) {
  const c = run.channels.find(x => x.id === s.channel);
  if (!c) return;
  const d = deviceRow(c.device_id, c.device);
  if (s.status === 'ok') { d.ok++; d.lastOkMs = Date.now(); } else { d.failed++; }
  showCounts(d);
}
function onEvent(e) {
  const li = document.createElement('li');
  li.textContent = fmt(e.t_s) + ' ' + e.kind + (e.device ? ' [' + e.device + ']' : '') + ': ' + e.message;
  $('events').prepend(li);
  if (e.device_id === undefined) return;
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
function scheduleRedraw() {
  if (redrawPending) return;
  redrawPending = true;
  setTimeout(() => {
    redrawPending = false;
    const w = Number($('window').value);
    chart.options.scales.x.min = w > 0 ? Math.max(lastT - w, Math.min(0, lastT)) : undefined;
    chart.update('none');
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
  source.addEventListener('status', m => { $('status').textContent = JSON.parse(m.data).status; });
  source.addEventListener('event', m => onEvent(JSON.parse(m.data)));
  source.addEventListener('sample', m => onSample(JSON.parse(m.data)));
  source.addEventListener('frames', m => {
    const f = JSON.parse(m.data);
    $('frame-count').textContent = f.count; $('frame-time').textContent = fmt(f.last_t_s);
  });
}
// A new time origin moves every point: start again from the run's beginning.
function restart() {
  source.close(); clockBasis = null; lastT = 0;
  for (const ds of series.values()) ds.data = [];
  for (const d of devices.values()) { d.ok = 0; d.failed = 0; d.lastOkMs = null; }
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
