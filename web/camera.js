// The viewer page's camera: orbit, pan and zoom with the mouse on the image, and the reset view.

import { $, viewer } from './session.js';
import { syncStructureInputs } from './settings.js';
import { requestRender } from './stream.js';

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

export function setupCameraControls() {
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

export function resetView() {
  viewer.doc.camera = JSON.parse(JSON.stringify(viewer.initialCamera));
  syncStructureInputs();
  requestRender(false);
}
