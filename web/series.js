// The viewer page's time series, movie and help: a step slider with play and pause, the step's
// simulation time and cycle, the colour range over all steps or this step's; a movie of the view
// made on the server with its progress, cancel and download; and the overlay of mouse and keys.
// The page's start (viewer.js) calls startSeries().

import { syncControls } from './panel.js';
import { $, apiJson, clearMessage, isNetworkError, serverGone, showMessage, viewer } from './session.js';
import { pump, requestRender, updateFrameSize } from './stream.js';
import { layerField, tf } from './transfer.js';

const series = {
  info: null,      // GET /api/series: steps (name, time, cycle where known), current step
  playing: false,
  moving: false,   // a step change in flight
  movie: null,     // the movie being made: { id, state, frames, done }
};
viewer.series = series;

export function postJson(path, body) {
  return apiJson(path, { method: 'POST', body: JSON.stringify(body), headers: { 'Content-Type': 'application/json' } });
}

// ---------------------------------------------------------------------------------------------
// Steps

function formatTime(t) {
  if (t === null || t === undefined) return 'time unknown';
  return `t = ${Math.abs(t) >= 1e4 || (t !== 0 && Math.abs(t) < 1e-3) ? t.toExponential(4) : Number(t.toPrecision(6))}`;
}

/// A step as the page names it: its file name, marked where it cannot be read (the reason in
/// the tooltip).
function showStepName(step) {
  $('step-name').textContent = step.error ? `${step.name} (unreadable)` : step.name;
  $('step-name').title = step.error || '';
}

/// The step after step i that can be read (i itself when no other can).
function nextReadable(i) {
  const steps = series.info.steps;
  for (let k = 1; k <= steps.length; k++) {
    const j = (i + k) % steps.length;
    if (!steps[j].error) return j;
  }
  return i;
}

/// The step on screen: its number, name, simulation time and cycle (from the step's own data).
function showStep() {
  const steps = series.info.steps;
  const i = series.info.current;
  $('step').max = steps.length - 1;
  $('step').value = i;
  $('step-out').textContent = `${i + 1}/${steps.length}`;
  showStepName(steps[i]);
  const sim = viewer.info.simulation || {};
  $('step-time').textContent = formatTime(sim.time);
  $('step-cycle').textContent = sim.cycle === null || sim.cycle === undefined ? 'cycle unknown' : `cycle ${sim.cycle}`;
}

/// The colour range the series' choice asks for: the field's range over all steps, or none (the
/// renderer maps each step's own range).
async function applySeriesRange(field) {
  if (!series.info) return;
  const t = tf();
  if ($('series-range').value === 'step') {
    delete t.range;
    return;
  }
  const r = await apiJson(`/api/series?field=${encodeURIComponent(field)}`);
  if (Array.isArray(r.range) && r.range[0] !== null) t.range = r.range;
}

/// Shows step i: the server loads it (or takes the step it prefetched) and the page renders the
/// scene there.
async function goToStep(i) {
  if (!series.info) return;
  const n = series.info.steps.length;
  i = ((i % n) + n) % n;
  series.moving = true;
  try {
    series.info = await postJson('/api/step', { index: i });
    viewer.info = await apiJson('/api/info');
    if ($('series-range').value === 'step') delete tf().range;
    syncControls();
    showStep();
    requestRender(false);
  } catch (e) {
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
    pause();
    try {
      series.info = await apiJson('/api/series'); // the step that failed is marked now
      showStep();
    } catch (again) {
      // the message above says enough
    }
  } finally {
    series.moving = false;
  }
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/// Waits until the frame on screen answers the newest request and is refined (at most `ms`).
async function waitShown(ms) {
  const end = performance.now() + ms;
  while (performance.now() < end) {
    const h = viewer.latest;
    if (!pump.inflight && !pump.want && h && h.request === viewer.lastRequest && h.final) return;
    await sleep(30);
  }
}

async function play() {
  if (series.playing || !series.info) return;
  series.playing = true;
  $('play').textContent = 'Pause';
  while (series.playing) {
    await waitShown(3000);
    await sleep(150);
    if (!series.playing) break;
    await goToStep(nextReadable(series.info.current));
  }
}

function pause() {
  series.playing = false;
  $('play').textContent = 'Play';
}

async function setupSeries() {
  series.info = await apiJson('/api/series');
  if (series.info.steps.length < 2) return;
  $('series-section').hidden = false;
  showStep();
  $('step').addEventListener('input', () => {
    const i = Number($('step').value);
    $('step-out').textContent = `${i + 1}/${series.info.steps.length}`;
    showStepName(series.info.steps[i]);
  });
  $('step').addEventListener('change', () => {
    pause();
    goToStep(Number($('step').value));
  });
  $('play').addEventListener('click', () => (series.playing ? pause() : play()));
  $('series-range').addEventListener('change', async () => {
    try {
      await applySeriesRange(layerField());
    } catch (e) {
      showMessage(e.message);
    }
    syncControls();
    requestRender(false);
  });
  // A new field keeps the series' choice of range.
  viewer.adjustRange = applySeriesRange;
}

// ---------------------------------------------------------------------------------------------
// Movie

function showMovie(m) {
  const first = !series.movie || series.movie.id !== m.id;
  series.movie = m;
  $('movie').hidden = false;
  if (first) $('movie').scrollIntoView({ block: 'nearest' });
  const rendering = m.state === 'rendering' || m.state === 'encoding';
  $('movie-progress').max = Math.max(1, m.frames);
  $('movie-progress').value = m.done;
  const text = {
    rendering: `frame ${m.done} of ${m.frames}`,
    encoding: 'encoding…',
    done: `done: ${m.frames} frames, ${((m.bytes || 0) / 1e6).toFixed(1)} MB`,
    cancelled: 'cancelled',
    failed: 'failed',
  };
  $('movie-text').textContent = text[m.state] || m.state;
  $('movie-cancel').hidden = !rendering;
  $('make-movie').disabled = rendering;
  const link = $('movie-download');
  link.hidden = m.state !== 'done';
  if (m.state === 'done') link.href = m.file;
}

/// Polls a background job of the server (`kind`: movie or picture) every `job.every` ms while it
/// runs and is still the one on the page (`job.current()`), showing each state; a failure says
/// `job.failed` with the reason, and a lost answer re-enables `job.button`.
export async function followJob(kind, id, job) {
  while (job.current() === id) {
    await sleep(job.every);
    let j;
    try {
      j = await apiJson(`/api/${kind}?id=${encodeURIComponent(id)}`);
    } catch (e) {
      if (isNetworkError(e)) serverGone();
      else showMessage(e.message);
      $(job.button).disabled = false;
      return;
    }
    job.show(j);
    if (j.state === 'failed') showMessage(`${job.failed}: ${j.error}`);
    if (!job.running(j.state)) return;
  }
}

function followMovie(id) {
  return followJob('movie', id, {
    current: () => series.movie && series.movie.id, every: 300, show: showMovie, button: 'make-movie',
    failed: 'The movie could not be made', running: (state) => state === 'rendering' || state === 'encoding',
  });
}

async function makeMovie() {
  if (!viewer.info.can_encode_movies) {
    showMessage('Movies need ffmpeg on the machine the viewer runs on, and it is not installed there: install ffmpeg '
      + 'and start the viewer again (or use `exabricks movie` with a folder for the frames).');
    return;
  }
  pause();
  updateFrameSize();
  $('make-movie').disabled = true;
  try {
    const m = await postJson('/api/movie', { scene: viewer.doc });
    clearMessage();
    showMovie(m);
    followMovie(m.id);
  } catch (e) {
    $('make-movie').disabled = false;
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  }
}

function setupMovie() {
  $('make-movie').addEventListener('click', makeMovie);
  $('movie-cancel').addEventListener('click', async () => {
    if (!series.movie) return;
    try {
      showMovie(await postJson('/api/movie/cancel', { id: series.movie.id }));
    } catch (e) {
      showMessage(e.message);
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Help and keys

function showHelp(show) {
  $('help').hidden = !show;
  if (show) $('help-close').focus();
}

function setupKeys() {
  $('help-button').addEventListener('click', () => showHelp($('help').hidden));
  $('help-close').addEventListener('click', () => showHelp(false));
  $('help').addEventListener('click', (e) => {
    if (e.target === $('help')) showHelp(false);
  });
  window.addEventListener('keydown', (e) => {
    if (e.key === 'Escape' && !$('help').hidden) {
      showHelp(false);
      e.preventDefault();
      return;
    }
    const t = e.target;
    if (t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLTextAreaElement) return;
    if (e.key === '?') {
      showHelp($('help').hidden);
      e.preventDefault();
    } else if (series.info && series.info.steps.length > 1 && !series.moving) {
      if (e.key === ' ' && !(t instanceof HTMLButtonElement)) {
        if (series.playing) pause();
        else play();
        e.preventDefault();
      } else if (e.key === 'ArrowRight' || e.key === 'ArrowLeft') {
        pause();
        goToStep(series.info.current + (e.key === 'ArrowRight' ? 1 : -1));
        e.preventDefault();
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// NaN and infinite values as holes

/// Reads the step on screen again with NaN and infinite values as holes (or refused), and says
/// how many cells became holes; a dataset that cannot be read so stays, with the reason.
async function setHoles(holes) {
  const box = $('nan-holes');
  box.disabled = true;
  try {
    const info = await postJson('/api/holes', { holes });
    const counted = info.holes;
    delete info.holes;
    viewer.info = info;
    syncControls();
    if (series.info) {
      series.info = await apiJson('/api/series');
      showStep();
    }
    requestRender(false);
    if (holes) showMessage(`${counted.cells} cells with NaN or infinite values are holes`, 'info');
    else clearMessage();
  } catch (e) {
    box.checked = !holes;
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  } finally {
    box.disabled = false;
  }
}

function setupHoles() {
  const box = $('nan-holes');
  box.checked = !!viewer.info.nan_as_holes;
  box.addEventListener('change', () => setHoles(box.checked));
}

export async function startSeries() {
  setupKeys();
  setupMovie();
  setupHoles();
  try {
    await setupSeries();
  } catch (e) {
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  }
}
