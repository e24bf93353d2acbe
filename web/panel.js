// The viewer page's panel shown from the scene document: the choosers, the range boxes and the
// switch to another field.

import { bounds } from './clip.js';
import { iso, renderIsoList } from './iso.js';
import { syncParticleControls } from './particles.js';
import { $, apiJson, isNetworkError, serverGone, showMessage, viewer } from './session.js';
import { colormapChoices } from './settings.js';
import { requestRender } from './stream.js';
import { effectiveRange, layer, layerField, refreshHistogram, tf } from './transfer.js';

// ---------------------------------------------------------------------------------------------
// Controls <-> document

export function fillSelect(select, options, value) {
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

/// A colour-map chooser: the built-in maps the scene's description offers for `key`, and "from
/// file" where the map is given by its points (a preset or a loaded scene's).
function fillColormaps(select, colormap, key) {
  const { choices, fallback } = colormapChoices(key);
  const maps = choices.map((n) => [n, n]);
  const custom = colormap && typeof colormap === 'object';
  fillSelect(select, custom ? maps.concat([['custom', 'from file']]) : maps, custom ? 'custom' : colormap || fallback);
}

/// A field as the choosers name it: "name [units]" where the data records units.
function fieldLabel(f) {
  return f.units ? `${f.name} [${f.units}]` : f.name;
}

export function syncControls() {
  const doc = viewer.doc;
  const fields = viewer.info.fields.map((f) => [f.name, fieldLabel(f)]);
  fillSelect($('field'), fields, layerField());
  fillColormaps($('colormap'), tf().colormap, 'layers[].transfer_function.colormap');
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
  fillColormaps($('iso-colormap'), (s.color_map || {}).colormap || 'cool-to-warm', 'iso.color_map.colormap');
  renderIsoList();
  syncParticleControls();
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
  $('spp').value = Math.round(Math.log2(doc.frame.samples_per_pixel || 1));
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

export function showRangeValue(element, v) {
  element.dataset.value = String(v);
  element.value = document.activeElement === element ? numberText(v, 7) : fittingNumberText(v, element);
  element.dataset.shown = element.value;
}

/// The number a range box stands for: its exact value while the text is the one shown.
export function rangeValue(element) {
  if (element.value === element.dataset.shown && element.dataset.value !== undefined) return Number(element.dataset.value);
  const text = element.value.trim();
  return text === '' ? NaN : Number(text);
}

export function setupRangeBoxes() {
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
export async function switchField(name) {
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
