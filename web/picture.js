// The viewer page's publication output: this view rendered on the server at a chosen size and
// samples per pixel, as 8- or 16-bit PNG, OpenEXR or PFM, with progress, cancel and the file to
// download under a name of the dataset, field and size.

import { followJob, postJson } from './series.js';
import { $, clearMessage, isNetworkError, serverGone, showMessage, viewer } from './session.js';

const picture = { job: null }; // the picture being rendered: { id, state, tiles, done, name }
viewer.picture = picture;

function showPicture(p) {
  picture.job = p;
  $('picture').hidden = false;
  const rendering = p.state === 'rendering';
  $('picture-progress').max = Math.max(1, p.tiles);
  $('picture-progress').value = p.done;
  const text = {
    rendering: `${Math.round((100 * p.done) / Math.max(1, p.tiles))} % of ${p.passes} passes`,
    done: `done: ${p.name}, ${((p.bytes || 0) / 1e6).toFixed(1)} MB`,
    cancelled: 'cancelled',
    failed: 'failed',
  };
  $('picture-text').textContent = text[p.state] || p.state;
  $('picture-cancel').hidden = !rendering;
  $('picture-start').disabled = rendering;
  const link = $('picture-download');
  link.hidden = p.state !== 'done';
  if (p.state === 'done') {
    link.href = p.file;
    link.download = p.name;
  }
}

function followPicture(id) {
  return followJob('picture', id, {
    current: () => picture.job && picture.job.id, every: 250, show: showPicture, button: 'picture-start',
    failed: 'The picture could not be rendered', running: (state) => state === 'rendering',
  });
}

async function startPicture() {
  const number = (id) => Number($(id).value);
  $('picture-start').disabled = true;
  try {
    const p = await postJson('/api/picture', {
      scene: viewer.doc, width: number('picture-width'), height: number('picture-height'),
      spp: number('picture-spp'), format: $('picture-format').value,
    });
    clearMessage();
    showPicture(p);
    followPicture(p.id);
  } catch (e) {
    $('picture-start').disabled = false;
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  }
}

/// The first time the panel opens: the view's aspect, at 2048 pixels on its longer side.
function proposeSize() {
  const [w, h] = viewer.sceneSize || [0, 0];
  if (picture.sized || !(w > 0 && h > 0)) return;
  picture.sized = true;
  const s = 2048 / Math.max(w, h);
  $('picture-width').value = Math.max(1, Math.round(w * s));
  $('picture-height').value = Math.max(1, Math.round(h * s));
}

function setupPicture() {
  $('picture-panel').addEventListener('toggle', proposeSize);
  $('picture-start').addEventListener('click', startPicture);
  $('picture-cancel').addEventListener('click', async () => {
    if (!picture.job) return;
    try {
      showPicture(await postJson('/api/picture/cancel', { id: picture.job.id }));
    } catch (e) {
      showMessage(e.message);
    }
  });
}

window.addEventListener('load', setupPicture);
