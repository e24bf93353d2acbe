// The viewer page's light for the path tracer: where the sun stands (azimuth and elevation in
// degrees; elevation above the plane across the camera's up, the sky's zenith; the sun shines
// from there, so pathtrace.sun_direction, the way its light travels, points the other way), and
// the environment's colours (the horizon's, and the sky's and ground's where set), picked as
// colours and held as linear radiance (brighter than 1: the picked colour keeps that brightness).

import { $, viewer } from './session.js';
import { requestRender } from './stream.js';

function pathtrace() {
  if (!viewer.doc.pathtrace || typeof viewer.doc.pathtrace !== 'object') viewer.doc.pathtrace = {};
  return viewer.doc.pathtrace;
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const scale = (a, s) => a.map((x) => x * s);
const add = (...vs) => [0, 1, 2].map((i) => vs.reduce((sum, v) => sum + v[i], 0));
const normalize = (a) => scale(a, 1 / Math.hypot(...a));

/// The sky's frame: zenith (the camera's up) and two directions across it.
function skyFrame() {
  const up = normalize((viewer.doc.camera && viewer.doc.camera.up) || [0, 0, 1]);
  const x = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const e1 = normalize(add(x, scale(up, -dot(x, up))));
  return { up, e1, e2: cross(up, e1) };
}

const degrees = Math.PI / 180;

function sunDirection(azimuth, elevation) {
  const { up, e1, e2 } = skyFrame();
  const c = Math.cos(elevation * degrees);
  const toSun = add(scale(e1, c * Math.cos(azimuth * degrees)), scale(e2, c * Math.sin(azimuth * degrees)),
    scale(up, Math.sin(elevation * degrees)));
  return scale(toSun, -1);
}

function sunAngles(direction) {
  const { up, e1, e2 } = skyFrame();
  const toSun = normalize(scale(direction, -1));
  const elevation = Math.asin(Math.max(-1, Math.min(1, dot(toSun, up)))) / degrees;
  const azimuth = (Math.atan2(dot(toSun, e2), dot(toSun, e1)) / degrees + 360) % 360;
  return { azimuth, elevation };
}

const toLinear = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
const toSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055);

/// A radiance as a colour #rrggbb and a brightness: the colour itself up to 1, and above it its
/// colour with the brightest channel at 1 (a picked colour is scaled by the brightness).
function colourOf(radiance) {
  const brightness = Math.max(1, ...radiance);
  const hex = radiance.map((c) => Math.round(255 * toSrgb(c / brightness)).toString(16).padStart(2, '0')).join('');
  return { hex: `#${hex}`, brightness };
}

function radianceOf(hex, brightness) {
  return [1, 3, 5].map((i) => toLinear(parseInt(hex.slice(i, i + 2), 16) / 255) * brightness);
}

const ENVIRONMENT = ['environment', 'sky', 'ground'];

export function syncLightControls() {
  const p = pathtrace();
  const { azimuth, elevation } = sunAngles(p.sun_direction || [-1, -1, -1]);
  $('sun-azimuth').value = azimuth.toFixed(0);
  $('sun-azimuth-out').textContent = `${azimuth.toFixed(0)}°`;
  $('sun-elevation').value = elevation.toFixed(0);
  $('sun-elevation-out').textContent = `${elevation.toFixed(0)}°`;
  const skyAndGround = Array.isArray(p.sky) || Array.isArray(p.ground);
  $('sky-and-ground').checked = skyAndGround;
  for (const key of ENVIRONMENT) {
    const value = Array.isArray(p[key]) ? p[key] : p.environment || [1, 1, 1];
    $(`${key}-colour`).value = colourOf(value).hex;
    if (key !== 'environment') $(`${key}-colour`).disabled = !skyAndGround;
  }
}

export function setupLightControls() {
  for (const id of ['sun-azimuth', 'sun-elevation']) {
    // Drafts while the slider moves, the refined view where it stops.
    $(id).addEventListener('input', () => {
      pathtrace().sun_direction = sunDirection(Number($('sun-azimuth').value), Number($('sun-elevation').value));
      syncLightControls();
      requestRender(true);
    });
    $(id).addEventListener('change', () => requestRender(false));
  }
  for (const key of ENVIRONMENT)
    $(`${key}-colour`).addEventListener('change', () => {
      const p = pathtrace();
      const now = Array.isArray(p[key]) ? p[key] : p.environment || [1, 1, 1];
      p[key] = radianceOf($(`${key}-colour`).value, colourOf(now).brightness);
      requestRender(false);
    });
  $('sky-and-ground').addEventListener('change', () => {
    const p = pathtrace();
    if ($('sky-and-ground').checked) {
      // A blue sky over a dark ground, as bright as the horizon.
      const b = colourOf(p.environment || [1, 1, 1]).brightness;
      p.sky = [0.35 * b, 0.55 * b, 1.0 * b];
      p.ground = [0.25 * b, 0.22 * b, 0.2 * b];
    } else {
      delete p.sky;
      delete p.ground;
    }
    syncLightControls();
    requestRender(false);
  });
}
