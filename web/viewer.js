// The exabricks viewer page: edits a scene document (the JSON of `exabricks render --scene`),
// sends it to the server on every change, and draws the frames the server streams back.
'use strict';

const token = new URLSearchParams(location.search).get('token') || '';
const urlSize = new URLSearchParams(location.search).get('size');
const $ = (id) => document.getElementById(id);

const viewer = {
  info: null,        // GET /api/info
  vocabulary: [],    // GET /api/vocabulary: the scalar settings of scene files
  doc: null,         // the scene document being edited
  initialCamera: null,
  histogram: null,
  lastRequest: 0,    // newest request the server accepted
  drawnSequence: 0,
  latest: null,      // header of the frame on screen
  metrics: { latencies: [], draftFrames: [], finals: [], framesDrawn: 0, errors: [], saved: [] },
};
window.exabricksViewer = viewer;

// ---------------------------------------------------------------------------------------------
// Server access

async function api(path, options = {}) {
  const headers = Object.assign({ 'X-Exabricks-Token': token }, options.headers || {});
  const response = await fetch(path, Object.assign({}, options, { headers, cache: 'no-store' }));
  return response;
}

async function apiJson(path, options = {}) {
  const response = await api(path, options);
  let body = null;
  try {
    body = await response.json();
  } catch (e) {
    body = { error: `${path}: ${response.status} ${response.statusText}` };
  }
  if (!response.ok) throw new Error(body.error || `${path}: ${response.status}`);
  return body;
}

/// Shows a message in the banner over the image, where the user looks (errors in red, kind 'info'
/// in blue); an empty text hides it. Errors are also kept for scripts and tests.
function showMessage(text, kind = 'error') {
  const banner = $('banner');
  $('message').textContent = text;
  banner.hidden = !text;
  banner.classList.toggle('info', kind === 'info');
  viewer.messageKind = text ? kind : null;
  if (text && kind === 'error') viewer.metrics.errors.push(text);
}

/// Hides the banner unless it says the server cannot be reached (that stays until it can).
function clearMessage() {
  if (viewer.messageKind !== 'offline') showMessage('');
}

const offlineText = 'The viewer has stopped or cannot be reached: start `exabricks view` again and reload this page.';

/// A fetch that failed without an answer: the server is gone (stopped, or the connection dropped).
function isNetworkError(e) {
  return e instanceof TypeError;
}

function serverGone() {
  if (!viewer.offline) viewer.metrics.errors.push(offlineText);
  viewer.offline = true;
  showMessage(offlineText, 'offline');
}

function serverBack() {
  if (!viewer.offline) return;
  viewer.offline = false;
  if (viewer.messageKind === 'offline') showMessage('');
}

// ---------------------------------------------------------------------------------------------
// Requests: one in flight; while the user drags, a new draft is asked for only once the previous
// one arrived (or after a short wait), so drafts are never cancelled before they can be shown.

const pump = { inflight: false, want: null, inputTime: null, awaiting: 0, awaitingSince: 0, timer: null };

function requestRender(interactive) {
  if (!viewer.doc) return;
  if (pump.inputTime === null) pump.inputTime = performance.now();
  if (!interactive) viewer.interactionEnd = performance.now();
  pump.want = { interactive: pump.want && !pump.want.interactive ? false : interactive };
  if (!interactive) pump.want.interactive = false;
  sendPending();
}

async function sendPending() {
  if (pump.inflight || !pump.want) return;
  const waitingForDraft = pump.awaiting > viewer.drawnRequest && performance.now() - pump.awaitingSince < 250;
  if (pump.want.interactive && waitingForDraft) {
    clearTimeout(pump.timer);
    pump.timer = setTimeout(sendPending, 30);
    return;
  }
  const want = pump.want;
  pump.want = null;
  pump.inflight = true;
  const inputTime = pump.inputTime;
  pump.inputTime = null;
  updateFrameSize();
  try {
    const body = JSON.stringify({ scene: viewer.doc, interactive: want.interactive });
    const r = await apiJson('/api/render', { method: 'POST', body, headers: { 'Content-Type': 'application/json' } });
    viewer.lastRequest = r.request;
    pump.awaiting = r.request;
    pump.awaitingSince = performance.now();
    viewer.lastInteractive = want.interactive;
    viewer.requestTimes.set(r.request, { input: inputTime, interactive: want.interactive });
    clearMessage();
  } catch (e) {
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  } finally {
    pump.inflight = false;
    if (pump.want) sendPending();
  }
}
viewer.requestTimes = new Map();
viewer.drawnRequest = 0;

// ---------------------------------------------------------------------------------------------
// The frame stream: records of u32 header length, header JSON, u32 JPEG length, JPEG.

async function readStream() {
  for (;;) {
    let response = null;
    try {
      response = await api('/api/stream');
    } catch (e) {
      serverGone(); // no answer at all: the server is not running (or not reachable)
    }
    if (response && !response.ok) {
      let text = `frame stream: ${response.status}`;
      try {
        text = (await response.json()).error || text;
      } catch (e) {
        // not JSON: keep the status
      }
      showMessage(text);
    } else if (response) {
      serverBack();
      try {
        await readFrames(response.body.getReader());
      } catch (e) {
        // the connection dropped
      }
      // The stream ended (a stopping server ends every stream): connect again soon, which tells
      // whether the server is still there.
      await new Promise((resolve) => setTimeout(resolve, 300));
      continue;
    }
    await new Promise((resolve) => setTimeout(resolve, 1000));
  }
}

async function readFrames(reader) {
  let buffer = new Uint8Array(0);
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    const joined = new Uint8Array(buffer.length + value.length);
    joined.set(buffer);
    joined.set(value, buffer.length);
    buffer = joined;
    for (;;) {
      if (buffer.length < 4) break;
      const view = new DataView(buffer.buffer, buffer.byteOffset, buffer.byteLength);
      const headerLength = view.getUint32(0, true);
      if (buffer.length < 8 + headerLength) break;
      const imageLength = view.getUint32(4 + headerLength, true);
      const total = 8 + headerLength + imageLength;
      if (buffer.length < total) break;
      const header = JSON.parse(new TextDecoder().decode(buffer.subarray(4, 4 + headerLength)));
      const image = buffer.slice(8 + headerLength, total);
      buffer = buffer.slice(total);
      onFrame(header, image);
    }
  }
}

async function onFrame(header, image) {
  if (header.keepalive) return;
  if (header.request < viewer.lastRequest) return; // superseded: late frames are dropped
  if (header.error) {
    showMessage(header.error);
    return;
  }
  const bitmap = await createImageBitmap(new Blob([image], { type: 'image/jpeg' }));
  if (header.sequence < viewer.drawnSequence || header.request < viewer.lastRequest) return;
  viewer.drawnSequence = header.sequence;
  const canvas = $('image');
  if (canvas.width !== viewer.doc.frame.width || canvas.height !== viewer.doc.frame.height) {
    canvas.width = viewer.doc.frame.width;
    canvas.height = viewer.doc.frame.height;
    layoutCanvas();
  }
  const ctx = canvas.getContext('2d');
  ctx.imageSmoothingEnabled = true;
  ctx.imageSmoothingQuality = header.draft ? 'low' : 'high';
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
  bitmap.close();
  frameDrawn(header);
}

function frameDrawn(header) {
  const now = performance.now();
  const m = viewer.metrics;
  m.framesDrawn++;
  viewer.latest = header;
  const times = viewer.requestTimes.get(header.request);
  if (times && times.input !== null && times.latencyDone !== true) {
    times.latencyDone = true;
    m.latencies.push(now - times.input);
  }
  if (header.draft) m.draftFrames.push(now);
  if (header.final && times && !times.finalDone) {
    times.finalDone = true;
    if (viewer.interactionEnd) m.finals.push({ request: header.request, ms: now - viewer.interactionEnd });
  }
  if (header.request > viewer.drawnRequest) viewer.drawnRequest = header.request;
  $('progress-bar').style.width = header.final || header.draft ? '0' : `${(100 * header.passes) / header.target_passes}%`;
  showStats(header, now);
  // For scripts that drive the page (tests, benchmarks): one event per frame on screen.
  window.dispatchEvent(new CustomEvent('exabricks-frame', { detail: header }));
  if (pump.want) sendPending();
}

function showStats(h, now) {
  const m = viewer.metrics;
  const recent = m.draftFrames.filter((t) => now - t < 1000).length;
  const rows = [
    ['frame', h.draft ? 'draft' : h.final ? 'refined' : 'refining'],
    ['resolution', `${h.width} × ${h.height}`],
    ['passes', `${h.passes} / ${h.target_passes}`],
    ['pass time', `${(h.render_seconds * 1000).toFixed(1)} ms`],
    ['since change', `${(h.since_request * 1000).toFixed(0)} ms`],
    ['samples/s', `${(h.samples_per_second / 1e6).toFixed(1)} M`],
    ['regions visible', `${h.visible_regions} of ${h.regions}`],
    ['drafts/s', `${recent}`],
    ['latency', m.latencies.length ? `${m.latencies[m.latencies.length - 1].toFixed(0)} ms` : '–'],
  ];
  $('stats').innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join('');
}

// ---------------------------------------------------------------------------------------------
// Vector helpers and the camera

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const length = (a) => Math.sqrt(dot(a, a));
const normalize = (a) => scale(a, 1 / (length(a) || 1));

/// Rotates v about the unit axis k by angle (Rodrigues).
function rotate(v, k, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  return add(add(scale(v, c), scale(cross(k, v), s)), scale(k, dot(k, v) * (1 - c)));
}

function orbit(dx, dy) {
  const cam = viewer.doc.camera;
  const up = normalize(cam.up);
  let offset = sub(cam.position, cam.look_at);
  offset = rotate(offset, up, -dx * 0.006);
  const right = normalize(cross(offset, up));
  const turned = rotate(offset, right, dy * 0.006);
  // Stay off the poles so that the view never flips over the up direction.
  const polar = Math.acos(Math.max(-1, Math.min(1, dot(normalize(turned), up))));
  if (polar > 0.02 && polar < Math.PI - 0.02) offset = turned;
  cam.position = add(cam.look_at, offset);
}

function pan(dx, dy) {
  const cam = viewer.doc.camera;
  const offset = sub(cam.position, cam.look_at);
  const forward = normalize(scale(offset, -1));
  const right = normalize(cross(forward, cam.up));
  const up = cross(right, forward);
  const canvas = $('image');
  const h = canvas.clientHeight || canvas.height;
  const extent = cam.orthographic ? cam.ortho_height : 2 * length(offset) * Math.tan((cam.fov * Math.PI) / 360);
  const move = add(scale(right, (-dx * extent) / h), scale(up, (dy * extent) / h));
  cam.position = add(cam.position, move);
  cam.look_at = add(cam.look_at, move);
}

function zoom(amount) {
  const cam = viewer.doc.camera;
  const factor = Math.exp(amount);
  if (cam.orthographic) cam.ortho_height *= factor;
  else cam.position = add(cam.look_at, scale(sub(cam.position, cam.look_at), factor));
}

function setupCameraControls() {
  const canvas = $('image');
  let drag = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    try {
      canvas.setPointerCapture(e.pointerId);
    } catch (err) {
      // a synthetic pointer cannot be captured
    }
    canvas.classList.add('dragging');
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey };
    canvas.focus();
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (dx === 0 && dy === 0) return;
    drag.x = e.clientX;
    drag.y = e.clientY;
    if (drag.pan) pan(dx, dy);
    else orbit(dx, dy);
    requestRender(true);
  });
  const end = () => {
    if (!drag) return;
    drag = null;
    canvas.classList.remove('dragging');
    requestRender(false);
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  let wheelTimer = null;
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    zoom(Math.max(-0.5, Math.min(0.5, e.deltaY * 0.001)));
    requestRender(true);
    clearTimeout(wheelTimer);
    wheelTimer = setTimeout(() => requestRender(false), 200);
  }, { passive: false });
  window.addEventListener('keydown', (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    if (e.key === 'r' || e.key === 'R') resetView();
  });
}

function resetView() {
  viewer.doc.camera = JSON.parse(JSON.stringify(viewer.initialCamera));
  requestRender(false);
}

// ---------------------------------------------------------------------------------------------
// Frame size

function updateFrameSize() {
  const frame = viewer.doc.frame;
  const choice = $('resolution').value;
  const max = viewer.info.limits.max_image_side;
  let w, h;
  if (choice === 'window') {
    const area = $('view');
    const dpr = window.devicePixelRatio || 1;
    w = Math.round(area.clientWidth * dpr);
    h = Math.round(area.clientHeight * dpr);
  } else if (choice === 'scene') {
    w = viewer.sceneSize[0];
    h = viewer.sceneSize[1];
  } else {
    w = h = Number(choice);
  }
  frame.width = Math.max(16, Math.min(max, w || 16));
  frame.height = Math.max(16, Math.min(max, h || 16));
}

function layoutCanvas() {
  const canvas = $('image');
  const dpr = window.devicePixelRatio || 1;
  if ($('resolution').value === 'window') {
    canvas.style.width = `${canvas.width / dpr}px`;
    canvas.style.height = `${canvas.height / dpr}px`;
  } else {
    canvas.style.width = '';
    canvas.style.height = '';
  }
}

// ---------------------------------------------------------------------------------------------
// Transfer function

function layer() {
  return viewer.doc.layers[0];
}

function tf() {
  const l = layer();
  if (!l.transfer_function) l.transfer_function = {};
  return l.transfer_function;
}

function fieldInfo(name) {
  const fields = viewer.info.fields;
  return fields.find((f) => f.name === name) || fields.find((f) => f.name === viewer.info.default_field);
}

function layerField() {
  return layer().field || viewer.info.default_field;
}

/// The value range the transfer function maps: its own, or the field's.
function effectiveRange() {
  const t = tf();
  if (Array.isArray(t.range) && t.range.length === 2) return [t.range[0], t.range[1]];
  const r = fieldInfo(layerField()).range;
  return [r[0] ?? 0, r[1] ?? 1];
}

/// The range a histogram and the normalisation use: a log scale cuts a non-positive low end six
/// decades below the high end, as the renderer does.
function normalisedRange() {
  let [lo, hi] = effectiveRange();
  if (tf().log && !(lo > 0)) lo = hi * 1e-6;
  return [lo, hi];
}

function opacityPoints() {
  const t = tf();
  if (!Array.isArray(t.opacity) || t.opacity.length === 0) t.opacity = [[0, 0], [1, 1]];
  return t.opacity;
}

function colormapSamples(colormap) {
  if (typeof colormap === 'string') return viewer.info.colormaps[colormap] || viewer.info.colormaps.viridis;
  if (colormap && Array.isArray(colormap.points)) {
    const pts = colormap.points;
    const out = [];
    for (let i = 0; i < 32; i++) {
      const x = i / 31;
      let k = 0;
      while (k < pts.length - 2 && pts[k + 1][0] < x) k++;
      const a = pts[k], b = pts[k + 1];
      const f = b[0] > a[0] ? Math.max(0, Math.min(1, (x - a[0]) / (b[0] - a[0]))) : 0;
      out.push([a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]), a[3] + f * (b[3] - a[3])]);
    }
    return out;
  }
  return viewer.info.colormaps.viridis;
}

const editor = { drag: -1, width: 300, height: 130, strip: 12 };

function editorPoint(p) {
  const h = editor.height - editor.strip;
  return [p[0] * (editor.width - 8) + 4, 4 + (1 - p[1]) * (h - 8)];
}

function editorValue(x, y) {
  const h = editor.height - editor.strip;
  return [Math.max(0, Math.min(1, (x - 4) / (editor.width - 8))), Math.max(0, Math.min(1, 1 - (y - 4) / (h - 8)))];
}

function drawEditor() {
  const canvas = $('tf-editor');
  const ctx = canvas.getContext('2d');
  const w = editor.width, h = editor.height, strip = editor.strip;
  ctx.clearRect(0, 0, w, h);
  // Histogram (log of the counts), then the colour map strip, then the opacity curve.
  const hist = viewer.histogram;
  if (hist && hist.counts.length) {
    const max = Math.log1p(Math.max(...hist.counts));
    ctx.fillStyle = 'rgba(150, 160, 170, 0.45)';
    const bw = (w - 8) / hist.counts.length;
    hist.counts.forEach((c, i) => {
      const bh = max > 0 ? (Math.log1p(c) / max) * (h - strip - 8) : 0;
      ctx.fillRect(4 + i * bw, h - strip - 4 - bh, Math.max(1, bw - 0.5), bh);
    });
  }
  const samples = colormapSamples(tf().colormap || 'viridis');
  samples.forEach((c, i) => {
    ctx.fillStyle = `rgb(${c.map((v) => Math.round(v * 255)).join(',')})`;
    ctx.fillRect(4 + (i * (w - 8)) / samples.length, h - strip, (w - 8) / samples.length + 1, strip);
  });
  const pts = opacityPoints().map(editorPoint);
  ctx.strokeStyle = '#f0f0f0';
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  ctx.moveTo(4, pts[0][1]);
  pts.forEach((p) => ctx.lineTo(p[0], p[1]));
  ctx.lineTo(w - 4, pts[pts.length - 1][1]);
  ctx.stroke();
  pts.forEach((p, i) => {
    ctx.fillStyle = i === editor.drag ? '#5aa9e6' : '#ffffff';
    ctx.beginPath();
    ctx.arc(p[0], p[1], 4, 0, 2 * Math.PI);
    ctx.fill();
  });
}

function setupEditor() {
  const canvas = $('tf-editor');
  const local = (e) => {
    const r = canvas.getBoundingClientRect();
    return [((e.clientX - r.left) * editor.width) / r.width, ((e.clientY - r.top) * editor.height) / r.height];
  };
  const nearest = (x, y) => {
    let best = -1, bestD = 8;
    opacityPoints().forEach((p, i) => {
      const q = editorPoint(p);
      const d = Math.hypot(q[0] - x, q[1] - y);
      if (d < bestD) { best = i; bestD = d; }
    });
    return best;
  };
  canvas.addEventListener('contextmenu', (e) => {
    e.preventDefault();
    const [x, y] = local(e);
    const i = nearest(x, y);
    if (i >= 0 && opacityPoints().length > 1) {
      opacityPoints().splice(i, 1);
      drawEditor();
      requestRender(false);
    }
  });
  canvas.addEventListener('dblclick', (e) => {
    const [x, y] = local(e);
    const v = editorValue(x, y);
    const pts = opacityPoints();
    let at = pts.findIndex((p) => p[0] > v[0]);
    if (at < 0) at = pts.length;
    pts.splice(at, 0, v);
    drawEditor();
    requestRender(false);
  });
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0) return;
    const [x, y] = local(e);
    editor.drag = nearest(x, y);
    if (editor.drag >= 0) canvas.setPointerCapture(e.pointerId);
    drawEditor();
  });
  canvas.addEventListener('pointermove', (e) => {
    if (editor.drag < 0) return;
    const [x, y] = local(e);
    const pts = opacityPoints();
    const v = editorValue(x, y);
    const lo = editor.drag > 0 ? pts[editor.drag - 1][0] : 0;
    const hi = editor.drag < pts.length - 1 ? pts[editor.drag + 1][0] : 1;
    pts[editor.drag] = [Math.max(lo, Math.min(hi, v[0])), v[1]];
    drawEditor();
    requestRender(true);
  });
  const end = () => {
    if (editor.drag < 0) return;
    editor.drag = -1;
    drawEditor();
    requestRender(false);
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
}

let histogramTimer = null;
function refreshHistogram() {
  clearTimeout(histogramTimer);
  histogramTimer = setTimeout(async () => {
    const [lo, hi] = normalisedRange();
    if (!(lo < hi)) return;
    const q = new URLSearchParams({ field: layerField(), bins: 150, lo, hi, log: tf().log ? 1 : 0 });
    try {
      viewer.histogram = await apiJson(`/api/histogram?${q}`);
    } catch (e) {
      viewer.histogram = null;
    }
    drawEditor();
  }, 60);
}

// ---------------------------------------------------------------------------------------------
// Iso-surfaces

const isoPalette = [[0.85, 0.85, 0.85], [0.95, 0.6, 0.3], [0.4, 0.7, 0.95], [0.6, 0.9, 0.5], [0.9, 0.5, 0.8]];

function iso() {
  if (!viewer.doc.iso) viewer.doc.iso = { values: [] };
  const s = viewer.doc.iso;
  if (!Array.isArray(s.values)) s.values = [];
  if (!Array.isArray(s.colors)) s.colors = [];
  return s;
}

/// The values an iso slider spans: the transfer function's range and scale when the iso-surfaces
/// show the volume's field (what the user sees), else the field's range (logarithmic for positive
/// data over more than three decades).
function isoScale() {
  const name = iso().field || layerField();
  if (name === layerField()) return { range: normalisedRange(), log: !!tf().log };
  const r = fieldInfo(name).range;
  const lo = r[0] ?? 0, hi = r[1] ?? 1;
  return { range: [lo, hi], log: lo > 0 && hi / lo > 1e3 };
}

function isoToSlider(v) {
  const { range: [lo, hi], log } = isoScale();
  if (!(hi > lo)) return 0.5;
  if (log) return (Math.log10(Math.max(v, lo)) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo));
  return (v - lo) / (hi - lo);
}

function sliderToIso(t) {
  const { range: [lo, hi], log } = isoScale();
  if (log) return 10 ** (Math.log10(lo) + t * (Math.log10(hi) - Math.log10(lo)));
  return lo + t * (hi - lo);
}

const hex = (c) => '#' + c.map((v) => Math.round(Math.max(0, Math.min(1, v)) * 255).toString(16).padStart(2, '0')).join('');
const fromHex = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255);

function renderIsoList() {
  const s = iso();
  const list = $('iso-list');
  list.innerHTML = '';
  s.values.forEach((value, i) => {
    const row = document.createElement('div');
    row.className = 'iso-row';
    const slider = document.createElement('input');
    slider.type = 'range';
    slider.min = 0;
    slider.max = 1;
    slider.step = 0.001;
    slider.value = isoToSlider(value);
    slider.className = 'iso-value-slider';
    const number = document.createElement('input');
    number.type = 'number';
    number.step = 'any';
    number.value = Number(value.toPrecision(5));
    const color = document.createElement('input');
    color.type = 'color';
    color.value = hex(s.colors.length ? s.colors[i % s.colors.length] : isoPalette[0]);
    color.disabled = !!s.color_field;
    const remove = document.createElement('button');
    remove.textContent = '×';
    remove.title = 'remove this iso-surface';
    slider.addEventListener('input', () => {
      s.values[i] = sliderToIso(Number(slider.value));
      number.value = Number(s.values[i].toPrecision(5));
      requestRender(true);
    });
    slider.addEventListener('change', () => requestRender(false));
    number.addEventListener('change', () => {
      const v = Number(number.value);
      if (!Number.isFinite(v)) return;
      s.values[i] = v;
      slider.value = isoToSlider(v);
      requestRender(false);
    });
    color.addEventListener('input', () => {
      while (s.colors.length < s.values.length) s.colors.push(isoPalette[s.colors.length % isoPalette.length]);
      s.colors[i] = fromHex(color.value);
      requestRender(false);
    });
    remove.addEventListener('click', () => {
      s.values.splice(i, 1);
      if (s.colors.length > i && s.colors.length > 1) s.colors.splice(i, 1);
      renderIsoList();
      requestRender(false);
    });
    row.append(slider, number, color, remove);
    list.append(row);
  });
}

// ---------------------------------------------------------------------------------------------
// Clipping

function bounds() {
  return viewer.info.bounds;
}

function applyClipPlane() {
  const clip = viewer.doc.clip || (viewer.doc.clip = {});
  if (!$('clip-plane-on').checked) {
    clip.planes = [];
    return;
  }
  const axis = Number($('clip-plane-axis').value);
  const b = bounds();
  const t = Number($('clip-plane-pos').value);
  const point = [(b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2];
  point[axis] = b[axis] + t * (b[axis + 3] - b[axis]);
  const normal = [0, 0, 0];
  normal[axis] = $('clip-plane-flip').checked ? -1 : 1;
  clip.planes = [{ point, normal }];
}

function applyClipBox() {
  const clip = viewer.doc.clip || (viewer.doc.clip = {});
  if (!$('clip-box-on').checked) {
    delete clip.box;
    return;
  }
  const b = bounds();
  const box = [];
  for (let k = 0; k < 6; k++) {
    const axis = k % 3;
    const t = Number($(`clip-box-${k}`).value);
    box.push(b[axis] + t * (b[axis + 3] - b[axis]));
  }
  for (let a = 0; a < 3; a++)
    if (!(box[a] < box[a + 3])) box[a + 3] = box[a] + 1e-6 * Math.max(1, Math.abs(b[a + 3] - b[a]));
  clip.box = box;
}

function buildClipBoxSliders() {
  const wrap = $('clip-box-sliders');
  const names = ['x min', 'y min', 'z min', 'x max', 'y max', 'z max'];
  names.forEach((name, k) => {
    const label = document.createElement('label');
    label.className = 'row';
    label.innerHTML = `<span>${name}</span><input type="range" id="clip-box-${k}" min="0" max="1" step="0.001" value="${k < 3 ? 0 : 1}">`;
    wrap.append(label);
    label.querySelector('input').addEventListener('input', () => {
      if (!$('clip-box-on').checked) return;
      applyClipBox();
      requestRender(true);
    });
    label.querySelector('input').addEventListener('change', () => {
      if ($('clip-box-on').checked) requestRender(false);
    });
  });
}

// ---------------------------------------------------------------------------------------------
// Controls <-> document

function fillSelect(select, options, value) {
  select.innerHTML = '';
  for (const [v, text] of options) {
    const o = document.createElement('option');
    o.value = v;
    o.textContent = text;
    o.title = text; // the whole name, where the panel shows its start
    select.append(o);
  }
  if (value !== undefined) select.value = value;
  select.title = select.selectedOptions.length ? select.selectedOptions[0].title : '';
}

// A chooser's tooltip names its choice in full (the panel may show only its start).
document.addEventListener('change', (e) => {
  const t = e.target;
  if (t instanceof HTMLSelectElement && t.selectedOptions.length) t.title = t.selectedOptions[0].title;
});

/// A field as the choosers name it: "name [units]" where the data records units.
function fieldLabel(f) {
  return f.units ? `${f.name} [${f.units}]` : f.name;
}

function syncControls() {
  const doc = viewer.doc;
  const fields = viewer.info.fields.map((f) => [f.name, fieldLabel(f)]);
  fillSelect($('field'), fields, layerField());
  const maps = Object.keys(viewer.info.colormaps).map((n) => [n, n]);
  const cm = tf().colormap;
  const custom = cm && typeof cm === 'object';
  fillSelect($('colormap'), custom ? maps.concat([['custom', 'from file']]) : maps, custom ? 'custom' : cm || 'viridis');
  $('volume-on').checked = doc.volume !== false;
  const [lo, hi] = effectiveRange();
  showRangeValue($('range-lo'), lo);
  showRangeValue($('range-hi'), hi);
  $('log-scale').checked = !!tf().log;
  const os = tf().opacity_scale;
  const base = viewer.info.default_opacity_scale;
  $('opacity-scale').value = typeof os === 'number' && base > 0 ? Math.log10(os / base) : 0;
  $('opacity-scale-out').textContent = typeof os === 'number' ? `×${(os / base).toPrecision(2)}` : 'auto';
  const s = iso();
  fillSelect($('iso-field'), [['', '(volume field)']].concat(fields), s.field || '');
  fillSelect($('iso-color-field'), [['', '(colour per value)']].concat(fields), s.color_field || '');
  const isoMap = s.color_map && typeof s.color_map.colormap === 'string' ? s.color_map.colormap : 'cool-to-warm';
  fillSelect($('iso-colormap'), maps, isoMap);
  renderIsoList();
  const clip = doc.clip || {};
  const plane = (clip.planes || [])[0];
  $('clip-plane-on').checked = !!plane;
  if (plane) {
    const axis = plane.normal.findIndex((v) => Math.abs(v) > 0.5);
    if (axis >= 0) {
      const b = bounds();
      $('clip-plane-axis').value = axis;
      $('clip-plane-flip').checked = plane.normal[axis] < 0;
      $('clip-plane-pos').value = (plane.point[axis] - b[axis]) / (b[axis + 3] - b[axis] || 1);
    }
  }
  const box = Array.isArray(clip.box) && clip.box.length === 6 ? clip.box : null;
  $('clip-box-on').checked = !!box;
  if (box) {
    const b = bounds();
    for (let k = 0; k < 6; k++) $(`clip-box-${k}`).value = (box[k] - b[k % 3]) / (b[(k % 3) + 3] - b[k % 3] || 1);
  }
  $('shading').value = doc.shading;
  const ao = (doc.ambient_occlusion && doc.ambient_occlusion.rays) || 0;
  $('ao-rays').value = ao;
  $('ao-rays-out').textContent = ao;
  $('spp').value = doc.frame.samples_per_pixel;
  $('spp-out').textContent = doc.frame.samples_per_pixel;
  $('rate').value = Math.log2(doc.frame.rate || 1);
  $('rate-out').textContent = doc.frame.rate;
  refreshHistogram();
}

// ---------------------------------------------------------------------------------------------
// Numbers in the range boxes: as many digits as fit (up to six), in plain or scientific notation,
// whichever is shorter; the box keeps the exact value for as long as its text is not edited, and
// shows it in full while it has the focus.

let measureContext = null;

function textWidth(text, element) {
  if (!measureContext) measureContext = document.createElement('canvas').getContext('2d');
  const style = getComputedStyle(element);
  measureContext.font = `${style.fontStyle} ${style.fontWeight} ${style.fontSize} ${style.fontFamily}`;
  return measureContext.measureText(text).width;
}

/// The shorter of plain and scientific notation of v with `digits` significant digits.
function numberText(v, digits) {
  if (!Number.isFinite(v)) return String(v);
  if (v === 0) return '0';
  const plain = String(Number(v.toPrecision(digits)));
  let [mantissa, exponent] = v.toExponential(digits - 1).split('e');
  if (mantissa.includes('.')) mantissa = mantissa.replace(/0+$/, '').replace(/\.$/, '');
  const scientific = `${mantissa}e${exponent.replace('+', '')}`;
  return scientific.length < plain.length ? scientific : plain;
}

/// The most precise text of v (six digits down to two) that fits the box.
function fittingNumberText(v, element) {
  const style = getComputedStyle(element);
  const room = element.clientWidth - parseFloat(style.paddingLeft || 0) - parseFloat(style.paddingRight || 0) - 2;
  for (let digits = 6; digits >= 2; digits--) {
    const text = numberText(v, digits);
    if (!(room > 0) || textWidth(text, element) <= room) return text;
  }
  return numberText(v, 2);
}

function showRangeValue(element, v) {
  element.dataset.value = String(v);
  element.value = document.activeElement === element ? numberText(v, 7) : fittingNumberText(v, element);
  element.dataset.shown = element.value;
}

/// The number a range box stands for: its exact value while the text is the one shown.
function rangeValue(element) {
  if (element.value === element.dataset.shown && element.dataset.value !== undefined) return Number(element.dataset.value);
  const text = element.value.trim();
  return text === '' ? NaN : Number(text);
}

function setupRangeBoxes() {
  for (const id of ['range-lo', 'range-hi']) {
    const element = $(id);
    element.addEventListener('focus', () => {
      if (element.value === element.dataset.shown) showRangeValue(element, Number(element.dataset.value));
    });
    element.addEventListener('blur', () => {
      if (element.value === element.dataset.shown) showRangeValue(element, Number(element.dataset.value));
    });
  }
  window.addEventListener('resize', () => {
    for (const id of ['range-lo', 'range-hi'])
      if ($(id).value === $(id).dataset.shown) showRangeValue($(id), Number($(id).dataset.value));
  });
}

/// A new field gets the first picture's transfer function for it (the server chooses mapping,
/// range and opacity from its values, as `render` does); the colour map stays.
async function switchField(name) {
  layer().field = name;
  const t = tf();
  try {
    const r = await apiJson(`/api/first-picture?field=${encodeURIComponent(name)}`);
    if (layerField() !== name) return; // switched again meanwhile
    const chosen = r.transfer_function;
    if (Array.isArray(chosen.range)) t.range = chosen.range;
    else delete t.range;
    t.log = !!chosen.log;
    if (Array.isArray(chosen.opacity)) t.opacity = chosen.opacity;
    else delete t.opacity;
    t.opacity_scale = chosen.opacity_scale;
    if (viewer.adjustRange) await viewer.adjustRange(name); // a series' choice of range
    const note = $('field-note');
    note.textContent = (r.notes || []).join('\n');
    note.hidden = !(r.notes || []).length;
  } catch (e) {
    // Without the server's choice: the field's own range, linear, and a warning.
    delete t.range;
    t.log = false;
    if (isNetworkError(e)) serverGone();
    else showMessage(`${e.message}: the new field keeps the previous opacity; check the transfer function`);
  }
  syncControls();
  requestRender(false);
}

function setupControls() {
  const on = (id, event, fn) => $(id).addEventListener(event, fn);
  on('volume-on', 'change', () => {
    viewer.doc.volume = $('volume-on').checked;
    requestRender(false);
  });
  on('field', 'change', () => switchField($('field').value));
  on('colormap', 'change', () => {
    if ($('colormap').value === 'custom') return;
    tf().colormap = $('colormap').value;
    drawEditor();
    requestRender(false);
  });
  on('preset-file', 'change', async () => {
    const file = $('preset-file').files[0];
    if (!file) return;
    try {
      const r = await apiJson('/api/transfer-function', { method: 'POST', body: await file.text() });
      tf().colormap = r.transfer_function.colormap;
      syncControls();
      requestRender(false);
    } catch (e) {
      showMessage(e.message);
    }
    $('preset-file').value = '';
  });
  const setRange = () => {
    const lo = rangeValue($('range-lo')), hi = rangeValue($('range-hi'));
    if (!(Number.isFinite(lo) && Number.isFinite(hi) && lo < hi)) {
      showMessage('The range needs two numbers, low below high.');
      return;
    }
    if (tf().log && !(lo > 0)) {
      showMessage('A log scale needs a positive low end.');
      return;
    }
    tf().range = [lo, hi];
    showRangeValue($('range-lo'), lo);
    showRangeValue($('range-hi'), hi);
    clearMessage();
    refreshHistogram();
    renderIsoList();
    requestRender(false);
  };
  on('range-lo', 'change', setRange);
  on('range-hi', 'change', setRange);
  on('range-reset', 'click', () => {
    delete tf().range;
    syncControls();
    requestRender(false);
  });
  on('log-scale', 'change', () => {
    tf().log = $('log-scale').checked;
    refreshHistogram();
    renderIsoList();
    requestRender(false);
  });
  on('opacity-scale', 'input', () => {
    const v = Number($('opacity-scale').value);
    const base = viewer.info.default_opacity_scale;
    if (Math.abs(v) < 0.025) tf().opacity_scale = 'auto';
    else tf().opacity_scale = base * 10 ** v;
    $('opacity-scale-out').textContent = Math.abs(v) < 0.025 ? 'auto' : `×${(10 ** v).toPrecision(2)}`;
    requestRender(true);
  });
  on('opacity-scale', 'change', () => requestRender(false));
  on('iso-add', 'click', () => {
    const s = iso();
    s.values.push(sliderToIso(0.5));
    if (s.colors.length < s.values.length) s.colors.push(isoPalette[(s.values.length - 1) % isoPalette.length]);
    renderIsoList();
    requestRender(false);
  });
  on('iso-field', 'change', () => {
    iso().field = $('iso-field').value;
    renderIsoList();
    requestRender(false);
  });
  on('iso-color-field', 'change', () => {
    iso().color_field = $('iso-color-field').value;
    renderIsoList();
    requestRender(false);
  });
  on('iso-colormap', 'change', () => {
    const s = iso();
    s.color_map = Object.assign({}, s.color_map || {}, { colormap: $('iso-colormap').value });
    requestRender(false);
  });
  for (const id of ['clip-plane-on', 'clip-plane-axis', 'clip-plane-flip']) {
    on(id, 'change', () => {
      applyClipPlane();
      requestRender(false);
    });
  }
  on('clip-plane-pos', 'input', () => {
    if (!$('clip-plane-on').checked) return;
    applyClipPlane();
    requestRender(true);
  });
  on('clip-plane-pos', 'change', () => {
    if ($('clip-plane-on').checked) requestRender(false);
  });
  on('clip-box-on', 'change', () => {
    applyClipBox();
    requestRender(false);
  });
  on('shading', 'change', () => {
    viewer.doc.shading = $('shading').value;
    requestRender(false);
  });
  on('ao-rays', 'input', () => {
    const n = Number($('ao-rays').value);
    viewer.doc.ambient_occlusion = Object.assign({}, viewer.doc.ambient_occlusion || {}, { rays: n });
    $('ao-rays-out').textContent = n;
  });
  on('ao-rays', 'change', () => requestRender(false));
  on('spp', 'input', () => ($('spp-out').textContent = $('spp').value));
  on('spp', 'change', () => {
    viewer.doc.frame.samples_per_pixel = Number($('spp').value);
    requestRender(false);
  });
  on('rate', 'input', () => ($('rate-out').textContent = (2 ** Number($('rate').value)).toPrecision(3)));
  on('rate', 'change', () => {
    viewer.doc.frame.rate = 2 ** Number($('rate').value);
    requestRender(false);
  });
  on('resolution', 'change', () => {
    layoutCanvas();
    requestRender(false);
  });
  on('reset-view', 'click', resetView);
  on('save-image', 'click', saveImage);
  on('save-scene', 'click', async () => {
    const r = await api('/api/scene');
    download(new Blob([await r.text()], { type: 'application/json' }), attachmentName(r, 'scene.json'));
  });
  on('load-scene', 'change', async () => {
    const file = $('load-scene').files[0];
    if (!file) return;
    try {
      const r = await apiJson('/api/scene', { method: 'POST', body: await file.text() });
      adoptDocument(r.document, r.has_camera);
      requestRender(false);
    } catch (e) {
      showMessage(e.message);
    }
    $('load-scene').value = '';
  });
  let resizeTimer = null;
  window.addEventListener('resize', () => {
    if ($('resolution').value !== 'window') return;
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => requestRender(false), 150);
  });
}

/// Saves the view on screen: waits for the changes not yet sent, then asks the server for that
/// request's image once refined (a view still refining is saved when refinement completes).
async function saveImage() {
  const button = $('save-image');
  button.disabled = true;
  try {
    for (let attempt = 0; attempt < 5; attempt++) {
      while (pump.inflight || pump.want) await new Promise((resolve) => setTimeout(resolve, 30));
      if (viewer.lastInteractive) {
        requestRender(false); // a drag's draft has no full-resolution image: ask for the refined one
        continue;
      }
      const request = viewer.lastRequest;
      if (!viewer.latest || !viewer.latest.final || viewer.latest.request !== request)
        showMessage('Saving the PNG when the image on screen is refined…', 'info');
      let r;
      try {
        r = await api(`/api/snapshot.png?request=${request}`);
      } catch (e) {
        serverGone();
        return;
      }
      if (r.ok) {
        if (viewer.messageKind === 'info') showMessage('');
        download(await r.blob(), attachmentName(r, 'exabricks.png'));
        viewer.metrics.saved.push(Number(r.headers.get('X-Exabricks-Request')));
        return;
      }
      let text = `Save PNG: ${r.status}`;
      try {
        text = (await r.json()).error || text;
      } catch (e) {
        // keep the status
      }
      if (r.status === 409 && viewer.lastRequest !== request) continue; // the view changed: save the new one
      showMessage(text);
      return;
    }
    showMessage('Save PNG: the view kept changing; save again once it is refined.');
  } finally {
    button.disabled = false;
  }
}

/// The file name a response's Content-Disposition gives (the dataset, field and size), else `fallback`.
function attachmentName(response, fallback) {
  const match = /filename="([^"]+)"/.exec(response.headers.get('Content-Disposition') || '');
  return match ? match[1] : fallback;
}

function download(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  setTimeout(() => {
    URL.revokeObjectURL(a.href);
    a.remove();
  }, 1000);
}

/// Fills every select bound to a choice setting (data-setting="KEY") with the names the server's
/// description offers.
function fillChoices() {
  for (const select of document.querySelectorAll('select[data-setting]')) {
    const setting = viewer.vocabulary.find((s) => s.key === select.dataset.setting);
    if (setting && setting.choices) fillSelect(select, setting.choices.map((c) => [c, c]), setting.default);
  }
}

/// The document's value of a setting ("section.leaf" or "leaf"), and setting it.
function settingValue(key) {
  const path = key.split('.');
  let v = viewer.doc;
  for (const p of path) v = v && typeof v === 'object' ? v[p] : undefined;
  return v;
}

function setSettingValue(key, value) {
  const path = key.split('.');
  let o = viewer.doc;
  for (const p of path.slice(0, -1)) o = o[p] && typeof o[p] === 'object' ? o[p] : (o[p] = {});
  o[path[path.length - 1]] = value;
}

/// Checkboxes bound to a boolean setting (data-setting="KEY", such as the legends): shown from
/// the document, and a change sets it and renders.
/// Number fields and choices bound the same way (the path tracer's settings): their limits and
/// help from the server's description of the setting.
function syncSettingBoxes() {
  for (const box of document.querySelectorAll('input[type=checkbox][data-setting]'))
    box.checked = !!settingValue(box.dataset.setting);
  for (const input of document.querySelectorAll('input[type=number][data-setting], select[data-setting]:not(#shading)')) {
    const v = settingValue(input.dataset.setting);
    if (v !== undefined) input.value = typeof v === 'number' ? Number(v.toPrecision(6)) : v;
  }
  // The path tracer's settings show while it is the integrator.
  const pathTraced = settingValue('integration.integrator') === 'pathtrace';
  for (const row of document.querySelectorAll('.path-only')) row.hidden = !pathTraced;
}

function setupSettingBoxes() {
  for (const box of document.querySelectorAll('input[type=checkbox][data-setting]')) {
    const setting = viewer.vocabulary.find((s) => s.key === box.dataset.setting);
    if (setting) box.title = box.title ? `${setting.help} (${box.title})` : setting.help;
    box.addEventListener('change', () => {
      setSettingValue(box.dataset.setting, box.checked);
      requestRender(false);
    });
  }
  for (const input of document.querySelectorAll('input[type=number][data-setting], select[data-setting]:not(#shading)')) {
    const setting = viewer.vocabulary.find((s) => s.key === input.dataset.setting);
    if (!setting) continue;
    input.title = setting.help;
    if (input.type === 'number') {
      if (setting.min !== undefined) input.min = setting.min;
      if (setting.max !== undefined) input.max = setting.max;
    }
    input.addEventListener('change', () => {
      if (input.type === 'number' && input.value.trim() === '') return; // being typed: nothing to set yet
      const value = input.type === 'number' ? Number(input.value) : input.value;
      if (input.type === 'number' && !input.checkValidity()) {
        showMessage(`${setting.key} must be in [${input.min}, ${input.max}]`);
        return;
      }
      setSettingValue(input.dataset.setting, value);
      syncSettingBoxes();
      requestRender(false);
    });
  }
}

/// Takes a whole scene document (from the server's own JSON writer) as the one being edited.
function adoptDocument(doc, hasCamera = true) {
  const camera = viewer.doc ? viewer.doc.camera : null;
  viewer.doc = doc;
  if (!hasCamera && camera) viewer.doc.camera = camera;
  viewer.sceneSize = [doc.frame.width, doc.frame.height];
  if (!Array.isArray(doc.layers) || doc.layers.length === 0) doc.layers = [{ field: '' }];
  syncControls();
  syncSettingBoxes();
}

// ---------------------------------------------------------------------------------------------

async function start() {
  try {
    viewer.info = await apiJson('/api/info');
    viewer.vocabulary = await apiJson('/api/vocabulary');
  } catch (e) {
    if (isNetworkError(e)) serverGone();
    else showMessage(`Cannot reach the viewer: ${e.message}`);
    return;
  }
  $('dataset-name').textContent = viewer.info.name;
  document.title = `${viewer.info.name} — exabricks`;
  buildClipBoxSliders();
  fillChoices();
  adoptDocument(viewer.info.document);
  viewer.initialCamera = JSON.parse(JSON.stringify(viewer.doc.camera));
  if (urlSize && /^\d+$/.test(urlSize)) {
    const sel = $('resolution');
    if (![...sel.options].some((o) => o.value === urlSize)) fillSelect(sel, [...sel.options].map((o) => [o.value, o.textContent]).concat([[urlSize, `${urlSize}²`]]));
    sel.value = urlSize;
  }
  setupCameraControls();
  setupEditor();
  setupControls();
  setupSettingBoxes();
  setupRangeBoxes();
  $('banner-close').addEventListener('click', () => showMessage(''));
  readStream();
  requestRender(false);
  startSeries();
}

start();
