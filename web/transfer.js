// The viewer page's transfer function: the layer's field and value range, and the editor of the
// opacity points over the field's histogram and the colour map.

import { $, apiJson, viewer } from './session.js';
import { requestRender } from './stream.js';

export function layer() {
  return viewer.doc.layers[0];
}

export function tf() {
  const l = layer();
  if (!l.transfer_function) l.transfer_function = {};
  return l.transfer_function;
}

export function fieldInfo(name) {
  const fields = viewer.info.fields;
  return fields.find((f) => f.name === name) || fields.find((f) => f.name === viewer.info.default_field);
}

export function layerField() {
  return layer().field || viewer.info.default_field;
}

/// The value range the transfer function maps: its own, or the field's.
export function effectiveRange() {
  const t = tf();
  if (Array.isArray(t.range) && t.range.length === 2) return [t.range[0], t.range[1]];
  const r = fieldInfo(layerField()).range;
  return [r[0] ?? 0, r[1] ?? 1];
}

/// The range a histogram and the normalisation use: a log scale cuts a non-positive low end six
/// decades below the high end, as the renderer does.
export function normalisedRange() {
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

export function drawEditor() {
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

export function setupEditor() {
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
export function refreshHistogram() {
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
