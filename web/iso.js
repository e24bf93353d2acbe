// The viewer page's iso-surfaces: a slider, a number and a colour per iso-value.

import { $, viewer } from './session.js';
import { requestRender } from './stream.js';
import { fieldInfo, layerField, normalisedRange, tf } from './transfer.js';

export const isoPalette = [[0.85, 0.85, 0.85], [0.95, 0.6, 0.3], [0.4, 0.7, 0.95], [0.6, 0.9, 0.5], [0.9, 0.5, 0.8]];

export function iso() {
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

export function sliderToIso(t) {
  const { range: [lo, hi], log } = isoScale();
  if (log) return 10 ** (Math.log10(lo) + t * (Math.log10(hi) - Math.log10(lo)));
  return lo + t * (hi - lo);
}

const hex = (c) => '#' + c.map((v) => Math.round(Math.max(0, Math.min(1, v)) * 255).toString(16).padStart(2, '0')).join('');
const fromHex = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255);

export function renderIsoList() {
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
