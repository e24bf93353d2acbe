// The viewer page's controls: each one edits its part of the scene document and asks for a
// render; and the files: the image and the scene saved, a scene loaded.

import { resetView } from './camera.js';
import { applyClipBox, applyClipPlane } from './clip.js';
import { iso, isoPalette, renderIsoList, sliderToIso } from './iso.js';
import { syncLightControls } from './lights.js';
import { setupParticleControls } from './particles.js';
import { rangeValue, showRangeValue, switchField, syncControls } from './panel.js';
import { $, api, apiJson, clearMessage, serverGone, showMessage, viewer } from './session.js';
import { syncSettingBoxes } from './settings.js';
import { layoutCanvas, pump, requestRender } from './stream.js';
import { drawEditor, refreshHistogram, tf } from './transfer.js';

const on = (id, event, fn) => $(id).addEventListener(event, fn);

/// The volume: shown or not, its field, colour map and preset file.
function setupVolumeControls() {
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
}

/// The value range the transfer function maps, its log scale and its opacity scale.
function setupRangeControls() {
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
}

/// Iso-surfaces: a new one, the field they show and what colours them.
function setupIsoControls() {
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
    if ($('iso-colormap').value === 'custom') return;
    const s = iso();
    s.color_map = Object.assign({}, s.color_map || {}, { colormap: $('iso-colormap').value });
    requestRender(false);
  });
}

/// The clip plane and the clip box.
function setupClipControls() {
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
}

/// Shading, ambient occlusion, samples per pixel, sampling rate and resolution (which the
/// window's size sets when it fits the window).
function setupQualityControls() {
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
  // Samples per pixel in powers of two, 1 to 1024 (path-traced views converge slowly).
  on('spp', 'input', () => ($('spp-out').textContent = 2 ** Number($('spp').value)));
  on('spp', 'change', () => {
    viewer.doc.frame.samples_per_pixel = 2 ** Number($('spp').value);
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
  let resizeTimer = null;
  window.addEventListener('resize', () => {
    if ($('resolution').value !== 'window') return;
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(() => requestRender(false), 150);
  });
}

/// The view reset, the image and the scene saved, a scene loaded.
function setupFileControls() {
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
}

/// Binds every control of the panel to its part of the document.
export function setupControls() {
  setupVolumeControls();
  setupRangeControls();
  setupIsoControls();
  setupParticleControls();
  setupClipControls();
  setupQualityControls();
  setupFileControls();
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

/// Takes a whole scene document (from the server's own JSON writer) as the one being edited.
export function adoptDocument(doc, hasCamera = true) {
  const camera = viewer.doc ? viewer.doc.camera : null;
  viewer.doc = doc;
  if (!hasCamera && camera) viewer.doc.camera = camera;
  viewer.sceneSize = [doc.frame.width, doc.frame.height];
  if (!Array.isArray(doc.layers) || doc.layers.length === 0) doc.layers = [{ field: '' }];
  syncControls();
  syncSettingBoxes();
  syncLightControls();
}
