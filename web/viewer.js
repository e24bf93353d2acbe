// The exabricks viewer page: edits a scene document (the JSON of `exabricks render --scene`),
// sends it to the server on every change, and draws the frames the server streams back.
// This module starts the page; the others each hold one part of it.

import { setupCameraControls } from './camera.js';
import { buildClipBoxSliders } from './clip.js';
import { adoptDocument, setupControls } from './controls.js';
import { setupLightControls } from './lights.js';
import { fillSelect, setupRangeBoxes, syncControls } from './panel.js';
import './picture.js';
import { startSeries } from './series.js';
import { $, apiJson, isNetworkError, serverGone, showMessage, viewer } from './session.js';
import { fillChoices, setupSettingBoxes, setupStructureInputs } from './settings.js';
import { readStream, requestRender } from './stream.js';
import { setupEditor } from './transfer.js';

const urlSize = new URLSearchParams(location.search).get('size');

// For scripts that drive the page (tests): shows the document's state in the panel again.
viewer.syncControls = syncControls;

async function start() {
  try {
    viewer.info = await apiJson('/api/info');
    viewer.vocabulary = await apiJson('/api/vocabulary');
    viewer.structure = await apiJson('/api/structure');
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
  // ?size=N (N² pixels), ?size=scene (the scene's own width and height) or ?size=window.
  if (urlSize && /^(\d+|scene|window)$/.test(urlSize)) {
    const sel = $('resolution');
    if (![...sel.options].some((o) => o.value === urlSize)) fillSelect(sel, [...sel.options].map((o) => [o.value, o.textContent]).concat([[urlSize, `${urlSize}²`]]));
    sel.value = urlSize;
  }
  setupCameraControls();
  setupEditor();
  setupControls();
  setupSettingBoxes();
  setupLightControls();
  setupStructureInputs();
  setupRangeBoxes();
  $('banner-close').addEventListener('click', () => showMessage(''));
  readStream();
  requestRender(false);
  startSeries();
}

start();
