// The viewer page's controls bound to settings of the scene file by name (data-setting="KEY"):
// choices, checkboxes and number fields, with the limits and help the server describes.

import { fillSelect } from './panel.js';
import { showMessage, viewer } from './session.js';
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
      syncSettingBoxes();
      requestRender(false);
    });
  }
}
