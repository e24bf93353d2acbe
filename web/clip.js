// The viewer page's clipping: a clip plane along an axis, and a clip box.

import { $, viewer } from './session.js';
import { requestRender } from './stream.js';

export function bounds() {
  return viewer.info.bounds;
}

export function applyClipPlane() {
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

export function applyClipBox() {
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

export function buildClipBoxSliders() {
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
