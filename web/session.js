// The viewer page's state and its access to the server: the scene document being edited and what
// the page measures (window.exabricksViewer, for scripts that drive the page), the API calls with
// the page's token, and the banner's messages, including the one while the server is gone.

const token = new URLSearchParams(location.search).get('token') || '';
export const $ = (id) => document.getElementById(id);

export const viewer = {
  info: null,        // GET /api/info
  vocabulary: [],    // GET /api/vocabulary: the scalar settings of scene files
  structure: [],     // GET /api/structure: the structured keys of scene files
  doc: null,         // the scene document being edited
  initialCamera: null,
  histogram: null,
  lastRequest: 0,    // newest request the server accepted
  drawnSequence: 0,
  latest: null,      // header of the frame on screen
  metrics: { latencies: [], draftFrames: [], finals: [], framesDrawn: 0, errors: [], saved: [] },
};
window.exabricksViewer = viewer;

// ---------------------------------------------------------------------------------------------
// Server access

export async function api(path, options = {}) {
  const headers = Object.assign({ 'X-Exabricks-Token': token }, options.headers || {});
  const response = await fetch(path, Object.assign({}, options, { headers, cache: 'no-store' }));
  return response;
}

export async function apiJson(path, options = {}) {
  const response = await api(path, options);
  let body = null;
  try {
    body = await response.json();
  } catch (e) {
    body = { error: `${path}: ${response.status} ${response.statusText}` };
  }
  if (!response.ok) throw new Error(body.error || `${path}: ${response.status}`);
  return body;
}

/// Shows a message in the banner over the image, where the user looks (errors in red, kind 'info'
/// in blue); an empty text hides it. Errors are also kept for scripts and tests.
export function showMessage(text, kind = 'error') {
  const banner = $('banner');
  $('message').textContent = text;
  banner.hidden = !text;
  banner.classList.toggle('info', kind === 'info');
  viewer.messageKind = text ? kind : null;
  if (text && kind === 'error') viewer.metrics.errors.push(text);
}

/// Hides the banner unless it says the server cannot be reached (that stays until it can).
export function clearMessage() {
  if (viewer.messageKind !== 'offline') showMessage('');
}

const offlineText = 'The viewer has stopped or cannot be reached: start `exabricks view` again and reload this page.';

/// A fetch that failed without an answer: the server is gone (stopped, or the connection dropped).
export function isNetworkError(e) {
  return e instanceof TypeError;
}

export function serverGone() {
  if (!viewer.offline) viewer.metrics.errors.push(offlineText);
  viewer.offline = true;
  showMessage(offlineText, 'offline');
}

export function serverBack() {
  if (!viewer.offline) return;
  viewer.offline = false;
  if (viewer.messageKind === 'offline') showMessage('');
}
