// The viewer page's particles: shown or not (a setting box), which species, their radius (a
// setting box), and the attribute and map that colour them. The section shows only where the
// dataset has particles.

import { fillSelect } from './panel.js';
import { $, viewer } from './session.js';
import { colormapChoices } from './settings.js';
import { requestRender } from './stream.js';

function particles() {
  if (!viewer.doc.particles || typeof viewer.doc.particles !== 'object') viewer.doc.particles = {};
  return viewer.doc.particles;
}

/// The attributes of the species shown (of every species when all are shown).
function attributes() {
  const species = viewer.info.particles || [];
  const chosen = particles().species || '';
  const names = new Set();
  for (const s of species) if (!chosen || s.species === chosen) for (const a of s.attributes) names.add(a);
  return [...names];
}

export function syncParticleControls() {
  const species = viewer.info.particles || [];
  $('particles-section').hidden = species.length === 0;
  if (!species.length) return;
  const p = particles();
  fillSelect($('particle-species'),
    [['', `every species (${species.reduce((n, s) => n + s.count, 0)})`]].concat(species.map((s) => [s.species, `${s.species} (${s.count})`])),
    p.species || '');
  fillSelect($('particle-color-by'), [['', '(one colour)']].concat(attributes().map((a) => [a, a])), p.color_by || '');
  const { choices, fallback } = colormapChoices('particles.color_map.colormap');
  const map = (p.color_map || {}).colormap;
  fillSelect($('particle-colormap'), choices.map((n) => [n, n]), typeof map === 'string' ? map : fallback);
  $('particle-log').checked = !!(p.color_map || {}).log;
}

export function setupParticleControls() {
  $('particle-species').addEventListener('change', () => {
    particles().species = $('particle-species').value;
    if (!attributes().includes(particles().color_by)) particles().color_by = '';
    syncParticleControls();
    requestRender(false);
  });
  $('particle-color-by').addEventListener('change', () => {
    particles().color_by = $('particle-color-by').value;
    requestRender(false);
  });
  $('particle-colormap').addEventListener('change', () => {
    const p = particles();
    p.color_map = Object.assign({}, p.color_map || {}, { colormap: $('particle-colormap').value });
    requestRender(false);
  });
  $('particle-log').addEventListener('change', () => {
    const p = particles();
    p.color_map = Object.assign({}, p.color_map || {}, { log: $('particle-log').checked });
    requestRender(false);
  });
}
