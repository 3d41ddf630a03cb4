// weft view's page (docs/view.md): shows the frames the server renders and
// sends the edits of its controls. Plain JavaScript, nothing from elsewhere.
'use strict';

const $ = (id) => document.getElementById(id);
let state = null;         // GET /api/state
let initialCamera = null;
let generation = 0;       // the newest edit the server took
let layout = 'side';
let showFiber = false;    // toggle layout: which layer shows
let lastError = null;     // the server's last build error

// --- edits: one in flight at a time; later ones merge into the next -------
let pending = null;
let inFlight = false;

function merge(a, b) {
  const out = Object.assign({}, a);
  for (const [k, v] of Object.entries(b)) {
    if (k === 'lights' || k === 'yarns') out[k] = (out[k] || []).concat(v);
    else if (v && typeof v === 'object' && !Array.isArray(v) && out[k]) out[k] = Object.assign({}, out[k], v);
    else out[k] = v;
  }
  return out;
}

function send(edit) {
  pending = pending ? merge(pending, edit) : edit;
  if (!inFlight) flush();
}

async function flush() {
  if (!pending) return;
  const body = JSON.stringify(pending);
  pending = null;
  inFlight = true;
  try {
    const res = await fetch('/api/edit', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body });
    const reply = await res.json();
    if (res.ok) {
      generation = Math.max(generation, reply.generation);
      showError('');
      // The server moved something (a colour beyond the model's reach): show it and why.
      if (reply.notes && reply.notes.length) { showNote(reply.notes.join('\n')); await loadState(); }
    } else {
      showError(reply.error || ('HTTP ' + res.status));
      await loadState();
    }
  } catch (e) {
    showError('no connection to weft view: ' + e.message);
  }
  inFlight = false;
  if (pending) flush();
}

function showNote(text) {
  $('note').hidden = !text;
  $('note').textContent = text;
}

function showError(text) {
  $('error').hidden = !text;
  $('error').textContent = text;
}

// --- frames: a long poll per visible layer -----------------------------------
function frameLoop(layer) {
  const img = $(layer);
  let seq = 0;
  let url = null;
  async function next() {
    if (layer === 'fiber' && !(state && state.ab)) { seq = 0; setTimeout(next, 300); return; }
    try {
      const res = await fetch(`/api/frame?layer=${layer}&after=${seq}`, { cache: 'no-store' });
      if (res.status === 200) {
        seq = Number(res.headers.get('X-Weft-Seq'));
        const blob = await res.blob();
        const old = url;
        url = URL.createObjectURL(blob);
        img.src = url;
        if (old) URL.revokeObjectURL(old);
        img.dataset.seq = String(seq);
        img.dataset.generation = res.headers.get('X-Weft-Generation');
        img.dataset.spp = res.headers.get('X-Weft-Spp');
        img.dataset.secondsPerSpp = res.headers.get('X-Weft-Seconds-Per-Spp');
        img.dataset.width = res.headers.get('X-Weft-Width');
        img.dataset.height = res.headers.get('X-Weft-Height');
        const spp = Number(img.dataset.spp);
        const sps = Number(img.dataset.secondsPerSpp);
        $(layer + '-info').textContent = spp === 0 ? '(preview)'
          : `${spp} spp · ${sps < 1 ? (sps * 1000).toFixed(0) + ' ms' : sps.toFixed(2) + ' s'} per sample`;
        next();
      } else if (res.status === 204) {
        next();
      } else {
        setTimeout(next, 500);
      }
    } catch (e) {
      setTimeout(next, 1000);
    }
  }
  next();
}

async function statsLoop() {
  try {
    const s = await (await fetch('/api/stats', { cache: 'no-store' })).json();
    const parts = [s.status];
    if (s.neural) parts.push(`neural ${s.neural.spp}/${state ? state.spp_cap : '?'} spp`);
    if (s.fiber) parts.push(`fiber ${s.fiber.spp} spp`);
    if (s.neural && s.fiber && s.neural.seconds_per_spp > 0)
      parts.push(`fiber/neural time per sample ${(s.fiber.seconds_per_spp / s.neural.seconds_per_spp).toFixed(1)}x`);
    if (s.ssim !== null && s.ssim !== undefined) parts.push(`SSIM ${s.ssim.toFixed(3)}`);
    $('status').textContent = parts.join(' · ');
    $('status').dataset.ssim = s.ssim === null ? '' : String(s.ssim);
    // A build that failed put the last good scene back: show it and why.
    if (s.error && s.error !== lastError) { showError(s.error); await loadState(); }
    lastError = s.error;
  } catch (e) {
    $('status').textContent = 'no connection to weft view';
  }
  setTimeout(statsLoop, 500);
}

// --- camera: orbit, pan, zoom about camera.to ---------------------------------
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => mul(a, 1 / Math.hypot(a[0], a[1], a[2]));

// Rodrigues: v turned by angle about the unit axis k.
function rotate(v, k, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  return add(add(mul(v, c), mul(cross(k, v), s)), mul(k, dot(k, v) * (1 - c)));
}

function orbit(dx, dy) {
  const cam = state.camera;
  const up = norm(cam.up);
  let offset = sub(cam.from, cam.to);
  offset = rotate(offset, up, -dx * 0.008);
  const right = norm(cross(offset, up));
  const turned = rotate(offset, right, dy * 0.008);
  // Not over the pole: the camera's up would flip.
  const polar = Math.acos(Math.max(-1, Math.min(1, dot(norm(turned), up))));
  if (polar > 0.02 && polar < Math.PI - 0.02) offset = turned;
  setCamera({ from: add(cam.to, offset) });
}

function pan(dx, dy, img) {
  const cam = state.camera;
  const offset = sub(cam.from, cam.to);
  const dist = Math.hypot(...offset);
  const forward = norm(mul(offset, -1));
  const right = norm(cross(forward, cam.up));
  const up = cross(right, forward);
  const perPixel = 2 * dist * Math.tan(cam.fov_deg * Math.PI / 360) / Math.min(img.clientWidth, img.clientHeight);
  const move = add(mul(right, -dx * perPixel), mul(up, dy * perPixel));
  setCamera({ from: add(cam.from, move), to: add(cam.to, move) });
}

function zoom(steps) {
  const cam = state.camera;
  const offset = mul(sub(cam.from, cam.to), Math.exp(steps * 0.0015));
  setCamera({ from: add(cam.to, offset) });
}

function setCamera(change) {
  Object.assign(state.camera, change);
  send({ camera: change });
}

function bindMouse(img) {
  let last = null;
  let mode = null;
  img.addEventListener('contextmenu', (e) => e.preventDefault());
  img.addEventListener('pointerdown', (e) => {
    if (!state) return;
    img.setPointerCapture(e.pointerId);
    img.classList.add('dragging');
    mode = e.button === 2 || e.shiftKey ? 'pan' : 'orbit';
    last = [e.clientX, e.clientY];
  });
  img.addEventListener('pointermove', (e) => {
    if (!last) return;
    const dx = e.clientX - last[0], dy = e.clientY - last[1];
    last = [e.clientX, e.clientY];
    if (mode === 'pan') pan(dx, dy, img); else orbit(dx, dy);
  });
  const end = () => { last = null; img.classList.remove('dragging'); };
  img.addEventListener('pointerup', end);
  img.addEventListener('pointercancel', end);
  img.addEventListener('wheel', (e) => { e.preventDefault(); if (state) zoom(e.deltaY); }, { passive: false });
}

// --- the panel ------------------------------------------------------------------
function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === 'text') e.textContent = v; else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

const hex = (rgb) => '#' + rgb.map((v) => Math.round(Math.max(0, Math.min(1, v)) * 255).toString(16).padStart(2, '0')).join('');
const unhex = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255);

// The family parameters the sliders change, with their labels.
const familyParams = [
  ['twist', 'Twist (alpha)'], ['fibers', 'Fibers (N)'], ['density', 'Density (rho)'],
  ['beta_r_deg', 'Gloss width (beta_R, deg)'], ['c_r', 'Gloss strength (C_R)'],
  ['beta_tt_deg', 'beta_TT (deg)'], ['gamma_tt_deg', 'gamma_TT (deg)'],
];

function buildYarns() {
  const box = $('yarns');
  box.replaceChildren();
  state.yarns.forEach((yarn, index) => {
    const div = el('div', { class: 'yarn', 'data-yarn': String(index) }, el('h2', { text: `yarn ${index}` }));
    const select = el('select', { 'data-role': 'model' });
    for (const m of state.models) select.append(el('option', { value: m.id, text: m.id + (m.family ? ' (family)' : m.colour ? ' (any colour)' : '') }));
    select.value = yarn.model;
    select.addEventListener('change', () => send({ yarns: [{ index, model: select.value }] }));
    div.append(el('label', { text: 'Model ' }, select));
    const model = state.models.find((m) => m.id === yarn.model);
    if (model && model.colour && !model.family) {
      // A colour model: the colour the yarn should look (sRGB), beyond the
      // model's reach moved to the nearest it shows.
      const colour = el('input', { type: 'color', 'data-role': 'appearance' });
      colour.value = yarn.appearance ? hex(yarn.appearance) : '#808080';
      colour.addEventListener('input', () => send({ yarns: [{ index, appearance: unhex(colour.value) }] }));
      div.append(el('label', { class: 'inline', text: 'Colour (as it looks) ' }, colour));
    } else if (model && model.family) {
      // A family model: the fibers' colour C_TT (each channel in [0, 1]).
      const colour = el('input', { type: 'color', 'data-role': 'colour' });
      colour.value = yarn.colour ? hex(yarn.colour) : '#808080';
      colour.addEventListener('input', () => send({ yarns: [{ index, colour: unhex(colour.value) }] }));
      div.append(el('label', { class: 'inline', text: 'Fiber colour (C_TT) ' }, colour));
    }
    if (model && model.family) {
      const point = yarn.yarn || model.centre;
      for (const [key, label] of familyParams) {
        const range = model.family[key];
        if (!range) continue;
        const [lo, hi] = Array.isArray(range) ? range : [range.lo, range.hi];
        const value = key === 'c_r' ? point.c_r[0] : point[key];
        const out = el('output', { text: String(value) });
        const input = el('input', { type: 'range', min: String(lo), max: String(hi), step: key === 'fibers' ? '1' : String((hi - lo) / 100), value: String(value), 'data-role': key });
        input.addEventListener('input', () => {
          const v = Number(input.value);
          out.textContent = key === 'fibers' ? String(v) : v.toFixed(3);
        });
        // Each yarn of a family is a model to make (about a second): sent
        // when the slider is let go, not at every step of a drag.
        input.addEventListener('change', () => {
          const v = Number(input.value);
          const next = Object.assign({}, yarn.yarn || model.centre);
          next[key] = key === 'c_r' ? [v, v, v] : v;
          yarn.yarn = next;
          send({ yarns: [{ index, yarn: next }] });
        });
        div.append(el('label', { text: label + ' ' }, out, input));
      }
    }
    box.append(div);
  });
}

function buildLights() {
  const box = $('lights');
  box.replaceChildren();
  state.lights.forEach((light, index) => {
    const out = el('output', { text: light.strength.toFixed(2) });
    const input = el('input', { type: 'range', min: '0', max: '4', step: '0.05', value: String(light.strength), 'data-role': 'light' });
    input.addEventListener('input', () => {
      out.textContent = Number(input.value).toFixed(2);
      send({ lights: [{ index, strength: Number(input.value) }] });
    });
    box.append(el('label', { text: `${light.type} ${index} strength ` }, out, input));
  });
}

function fillControls() {
  $('scene-name').textContent = state.scene_name;
  $('fov').value = state.camera.fov_deg;
  $('fov-value').textContent = state.camera.fov_deg.toFixed(1) + '°';
  $('width').value = state.film.width;
  $('height').value = state.film.height;
  $('spp-cap').value = state.spp_cap;
  $('exposure').value = state.exposure;
  $('exposure-value').textContent = state.exposure.toFixed(1);
  $('ab').checked = state.ab;
  $('save').disabled = !state.can_save;
  document.documentElement.style.setProperty('--aspect', `${state.film.width} / ${state.film.height}`);
  buildYarns();
  buildLights();
  applyLayout();
}

async function loadState() {
  state = await (await fetch('/api/state', { cache: 'no-store' })).json();
  generation = Math.max(generation, state.generation);
  if (!initialCamera) initialCamera = JSON.parse(JSON.stringify(state.camera));
  fillControls();
}

function applyLayout() {
  const ab = state && state.ab;
  $('fiber-view').hidden = !ab || (layout === 'toggle' && !showFiber);
  $('neural-view').hidden = ab && layout === 'toggle' && showFiber;
}

function bindControls() {
  $('fov').addEventListener('input', () => {
    const v = Number($('fov').value);
    $('fov-value').textContent = v.toFixed(1) + '°';
    setCamera({ fov_deg: v });
  });
  const film = () => {
    const width = Number($('width').value), height = Number($('height').value);
    document.documentElement.style.setProperty('--aspect', `${width} / ${height}`);
    send({ film: { width, height } });
  };
  $('width').addEventListener('change', film);
  $('height').addEventListener('change', film);
  $('spp-cap').addEventListener('change', () => send({ spp_cap: Number($('spp-cap').value) }));
  $('exposure').addEventListener('input', () => {
    $('exposure-value').textContent = Number($('exposure').value).toFixed(1);
    send({ exposure: Number($('exposure').value) });
  });
  $('reset-camera').addEventListener('click', () => setCamera(JSON.parse(JSON.stringify(initialCamera))));
  $('ab').addEventListener('change', () => { state.ab = $('ab').checked; applyLayout(); send({ ab: state.ab }); });
  $('ab-layout').addEventListener('change', () => { layout = $('ab-layout').value; applyLayout(); });
  document.addEventListener('keydown', (e) => {
    if ((e.key === 'b' || e.key === 'B') && e.target.tagName !== 'INPUT') { showFiber = !showFiber; applyLayout(); }
  });
  $('save').addEventListener('click', async () => {
    $('saved').textContent = 'saving…';
    const res = await fetch('/api/save', { method: 'POST', body: '{}' });
    const reply = await res.json();
    if (res.ok) {
      $('saved').textContent = `${reply.scene}, ${reply.exr}, ${reply.png} (${reply.spp} spp) in ${reply.dir}`;
      $('saved').dataset.scene = reply.scene;
    } else {
      $('saved').textContent = '';
      showError(reply.error);
    }
  });
  bindMouse($('neural'));
  bindMouse($('fiber'));
}

bindControls();
// The first frame does not wait for the state: the view is there already.
frameLoop('neural');
loadState().then(() => {
  frameLoop('fiber');
  statsLoop();
}).catch((e) => showError('cannot reach weft view: ' + e.message));
