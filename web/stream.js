// The viewer page's render requests and the frames the server streams back: one request in flight,
// drafts while the user drags, each frame drawn on the canvas with its statistics, and the frame
// size the page asks for.

import { $, api, apiJson, clearMessage, isNetworkError, serverBack, serverGone, showMessage, viewer } from './session.js';

// ---------------------------------------------------------------------------------------------
// Requests: one in flight; while the user drags, a new draft is asked for only once the previous
// one arrived (or after a short wait), so drafts are never cancelled before they can be shown.

export const pump = { inflight: false, want: null, inputTime: null, awaiting: 0, awaitingSince: 0, timer: null };

export function requestRender(interactive) {
  if (!viewer.doc) return;
  if (pump.inputTime === null) pump.inputTime = performance.now();
  if (!interactive) viewer.interactionEnd = performance.now();
  pump.want = { interactive: pump.want && !pump.want.interactive ? false : interactive };
  if (!interactive) pump.want.interactive = false;
  sendPending();
}

async function sendPending() {
  if (pump.inflight || !pump.want) return;
  const waitingForDraft = pump.awaiting > viewer.drawnRequest && performance.now() - pump.awaitingSince < 250;
  if (pump.want.interactive && waitingForDraft) {
    clearTimeout(pump.timer);
    pump.timer = setTimeout(sendPending, 30);
    return;
  }
  const want = pump.want;
  pump.want = null;
  pump.inflight = true;
  const inputTime = pump.inputTime;
  pump.inputTime = null;
  updateFrameSize();
  try {
    const body = JSON.stringify({ scene: viewer.doc, interactive: want.interactive });
    const r = await apiJson('/api/render', { method: 'POST', body, headers: { 'Content-Type': 'application/json' } });
    viewer.lastRequest = r.request;
    pump.awaiting = r.request;
    pump.awaitingSince = performance.now();
    viewer.lastInteractive = want.interactive;
    viewer.requestTimes.set(r.request, { input: inputTime, interactive: want.interactive });
    clearMessage();
  } catch (e) {
    if (isNetworkError(e)) serverGone();
    else showMessage(e.message);
  } finally {
    pump.inflight = false;
    if (pump.want) sendPending();
  }
}
viewer.requestTimes = new Map();
viewer.drawnRequest = 0;

// ---------------------------------------------------------------------------------------------
// The frame stream: records of u32 header length, header JSON, u32 JPEG length, JPEG.

export async function readStream() {
  for (;;) {
    let response = null;
    try {
      response = await api('/api/stream');
    } catch (e) {
      serverGone(); // no answer at all: the server is not running (or not reachable)
    }
    if (response && !response.ok) {
      let text = `frame stream: ${response.status}`;
      try {
        text = (await response.json()).error || text;
      } catch (e) {
        // not JSON: keep the status
      }
      showMessage(text);
    } else if (response) {
      serverBack();
      try {
        await readFrames(response.body.getReader());
      } catch (e) {
        // the connection dropped
      }
      // The stream ended (a stopping server ends every stream): connect again soon, which tells
      // whether the server is still there.
      await new Promise((resolve) => setTimeout(resolve, 300));
      continue;
    }
    await new Promise((resolve) => setTimeout(resolve, 1000));
  }
}

async function readFrames(reader) {
  let buffer = new Uint8Array(0);
  for (;;) {
    const { value, done } = await reader.read();
    if (done) return;
    const joined = new Uint8Array(buffer.length + value.length);
    joined.set(buffer);
    joined.set(value, buffer.length);
    buffer = joined;
    for (;;) {
      if (buffer.length < 4) break;
      const view = new DataView(buffer.buffer, buffer.byteOffset, buffer.byteLength);
      const headerLength = view.getUint32(0, true);
      if (buffer.length < 8 + headerLength) break;
      const imageLength = view.getUint32(4 + headerLength, true);
      const total = 8 + headerLength + imageLength;
      if (buffer.length < total) break;
      const header = JSON.parse(new TextDecoder().decode(buffer.subarray(4, 4 + headerLength)));
      const image = buffer.slice(8 + headerLength, total);
      buffer = buffer.slice(total);
      onFrame(header, image);
    }
  }
}

async function onFrame(header, image) {
  if (header.keepalive) return;
  if (header.request < viewer.lastRequest) return; // superseded: late frames are dropped
  if (header.error) {
    showMessage(header.error);
    return;
  }
  const bitmap = await createImageBitmap(new Blob([image], { type: 'image/jpeg' }));
  if (header.sequence < viewer.drawnSequence || header.request < viewer.lastRequest) return;
  viewer.drawnSequence = header.sequence;
  const canvas = $('image');
  if (canvas.width !== viewer.doc.frame.width || canvas.height !== viewer.doc.frame.height) {
    canvas.width = viewer.doc.frame.width;
    canvas.height = viewer.doc.frame.height;
    layoutCanvas();
  }
  const ctx = canvas.getContext('2d');
  ctx.imageSmoothingEnabled = true;
  ctx.imageSmoothingQuality = header.draft ? 'low' : 'high';
  ctx.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
  bitmap.close();
  frameDrawn(header);
}

function frameDrawn(header) {
  const now = performance.now();
  const m = viewer.metrics;
  m.framesDrawn++;
  viewer.latest = header;
  const times = viewer.requestTimes.get(header.request);
  if (times && times.input !== null && times.latencyDone !== true) {
    times.latencyDone = true;
    m.latencies.push(now - times.input);
  }
  if (header.draft) m.draftFrames.push(now);
  if (header.final && times && !times.finalDone) {
    times.finalDone = true;
    if (viewer.interactionEnd) m.finals.push({ request: header.request, ms: now - viewer.interactionEnd });
  }
  if (header.request > viewer.drawnRequest) viewer.drawnRequest = header.request;
  $('progress-bar').style.width = header.final || header.draft ? '0' : `${(100 * header.passes) / header.target_passes}%`;
  showStats(header, now);
  // For scripts that drive the page (tests, benchmarks): one event per frame on screen.
  window.dispatchEvent(new CustomEvent('exabricks-frame', { detail: header }));
  if (pump.want) sendPending();
}

function showStats(h, now) {
  const m = viewer.metrics;
  const recent = m.draftFrames.filter((t) => now - t < 1000).length;
  const rows = [
    ['frame', h.draft ? 'draft' : h.final ? 'refined' : 'refining'],
    ['resolution', `${h.width} × ${h.height}`],
    ['passes', `${h.passes} / ${h.target_passes}`],
    ['pass time', `${(h.render_seconds * 1000).toFixed(1)} ms`],
    ['since change', `${(h.since_request * 1000).toFixed(0)} ms`],
    ['samples/s', `${(h.samples_per_second / 1e6).toFixed(1)} M`],
    ['regions visible', `${h.visible_regions} of ${h.regions}`],
    ['drafts/s', `${recent}`],
    ['latency', m.latencies.length ? `${m.latencies[m.latencies.length - 1].toFixed(0)} ms` : '–'],
  ];
  if (h.data) rows.unshift(['data', h.data]); // coarse levels first: what the frame shows
  $('stats').innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join('');
}

// ---------------------------------------------------------------------------------------------
// Frame size

export function updateFrameSize() {
  const frame = viewer.doc.frame;
  const choice = $('resolution').value;
  const max = viewer.info.limits.max_image_side;
  let w, h;
  if (choice === 'window') {
    const area = $('view');
    const dpr = window.devicePixelRatio || 1;
    w = Math.round(area.clientWidth * dpr);
    h = Math.round(area.clientHeight * dpr);
  } else if (choice === 'scene') {
    w = viewer.sceneSize[0];
    h = viewer.sceneSize[1];
  } else {
    w = h = Number(choice);
  }
  frame.width = Math.max(16, Math.min(max, w || 16));
  frame.height = Math.max(16, Math.min(max, h || 16));
}

export function layoutCanvas() {
  const canvas = $('image');
  const dpr = window.devicePixelRatio || 1;
  if ($('resolution').value === 'window') {
    canvas.style.width = `${canvas.width / dpr}px`;
    canvas.style.height = `${canvas.height / dpr}px`;
  } else {
    canvas.style.width = '';
    canvas.style.height = '';
  }
}
