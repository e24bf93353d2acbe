// The viewer page's controls bound to settings of the scene file by name (data-setting="KEY"):
// choices, checkboxes and number fields, with the limits and help the server describes; and those
// bound to structured keys (data-structure="camera.fov"), with the limits, choices and help of the
// server's description of the scene's structure.

import { fillSelect } from './panel.js';
import { $, showMessage, viewer } from './session.js';
import { requestRender } from './stream.js';

/// Fills every select bound to a choice setting (data-setting="KEY") with the names the server's
/// description offers.
export function fillChoices() {
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
export function syncSettingBoxes() {
  for (const box of document.querySelectorAll('input[type=checkbox][data-setting]'))
    box.checked = !!settingValue(box.dataset.setting);
  for (const input of document.querySelectorAll('input[type=number][data-setting], select[data-setting]:not(#shading)')) {
    const v = settingValue(input.dataset.setting);
    if (v !== undefined) input.value = typeof v === 'number' ? Number(v.toPrecision(6)) : v;
  }
  // The path tracer's settings show while it is the integrator.
  const pathTraced = settingValue('integration.integrator') === 'pathtrace';
  for (const row of document.querySelectorAll('.path-only')) row.hidden = !pathTraced;
  syncStructureInputs();
}

/// Path tracing chosen on the page samples as the command line's path tracer does unless the
/// view already has a noise target: the server's defaults (a target, at most that many samples,
/// denoised).
function startPathTracing(integrator) {
  const defaults = viewer.info.path_tracing_defaults;
  if (integrator !== 'pathtrace' || !defaults || settingValue('frame.noise_target') > 0) return;
  setSettingValue('frame.noise_target', defaults.noise_target);
  setSettingValue('frame.samples_per_pixel', defaults.samples_per_pixel);
  setSettingValue('frame.denoise', defaults.denoise);
  $('spp').value = Math.round(Math.log2(defaults.samples_per_pixel));
  $('spp-out').textContent = defaults.samples_per_pixel;
}

export function setupSettingBoxes() {
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
      if (input.dataset.setting === 'integration.integrator') startPathTracing(value);
      syncSettingBoxes();
      requestRender(false);
    });
  }
}

// ---------------------------------------------------------------------------------------------
// Structured keys (GET /api/structure)

/// The description of a structured key: "iso.values" as the server names it, or a key of a camera
/// or transfer function under the key that holds one ("camera.fov", "iso.color_map.colormap").
export function structureEntry(path) {
  const exact = viewer.structure.find((e) => !e.object && e.key === path);
  if (exact) return exact;
  const dot = path.lastIndexOf('.');
  if (dot < 0) return undefined;
  const owner = structureEntry(path.slice(0, dot));
  return owner && viewer.structure.find((e) => e.object === owner.type && e.key === path.slice(dot + 1));
}

/// The built-in colour maps a transfer function's colormap key offers, and its default.
export function colormapChoices(path) {
  const entry = structureEntry(path);
  if (entry && entry.choices) return { choices: entry.choices, fallback: entry.default };
  return { choices: Object.keys(viewer.info.colormaps), fallback: 'viridis' };
}

/// The interval a described number lies in, as "(0, 180)" or "[0, ∞)"; and whether v lies in it.
function interval(entry) {
  const lo = entry.min === undefined ? '(-∞' : `${entry.min_exclusive ? '(' : '['}${entry.min}`;
  const hi = entry.max === undefined ? '∞)' : `${entry.max}${entry.max_exclusive ? ')' : ']'}`;
  return `${lo}, ${hi}`;
}

function within(entry, v) {
  if (!Number.isFinite(v)) return false;
  if (entry.min !== undefined && (entry.min_exclusive ? !(v > entry.min) : !(v >= entry.min))) return false;
  return entry.max === undefined || (entry.max_exclusive ? v < entry.max : v <= entry.max);
}

const structureInputs = () => document.querySelectorAll('input[type=number][data-structure]');

/// Number fields bound to a structured key, shown from the document (the key's default where it
/// has none); disabled while the setting data-unless names is on (the field of view of an
/// orthographic camera).
export function syncStructureInputs() {
  for (const input of structureInputs()) {
    const entry = structureEntry(input.dataset.structure);
    let v = settingValue(input.dataset.structure);
    if (v === undefined && entry) v = entry.default;
    if (typeof v === 'number') input.value = Number(v.toPrecision(6));
    if (input.dataset.unless) input.disabled = !!settingValue(input.dataset.unless);
  }
}

export function setupStructureInputs() {
  for (const input of structureInputs()) {
    const key = input.dataset.structure;
    const entry = structureEntry(key);
    if (!entry) continue;
    input.title = entry.help;
    if (entry.min !== undefined) input.min = entry.min;
    if (entry.max !== undefined) input.max = entry.max;
    input.addEventListener('change', () => {
      if (input.value.trim() === '') return; // being typed: nothing to set yet
      const value = Number(input.value);
      if (!within(entry, value)) {
        showMessage(`${key} must be in ${interval(entry)}`);
        return;
      }
      setSettingValue(key, value);
      requestRender(false);
    });
  }
}
