// The fabatlas web customiser (Fab Forms Sec. 7, Fig. 9): one slider per
// exposed parameter confined to the valid region through the current point,
// a live preview of the snapped sample, cost/weight readout, starting points
// and a 2-D validity map; the point lives in the page URL, presets are
// OpenSCAD parameter sets, limits on properties shrink the valid region
// (Fab Forms Sec. 7.2), invalid stretches say why in words, and the design
// downloads as STL or 3MF. For a reconfigurable design (a state graph) it
// plays each transition with the objects moving along their motions, and for
// an invalid sample shows the first colliding time and highlights the
// colliding objects (Reconfigurables Sec. 5: when, then where). Talks only to
// the API of `fabatlas serve` (docs/viewer.md).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { installOptimise } from './optimise.js';

// State shared with tests (tests/viewer/browser_test.mjs reads it).
const state = {
  ready: false,
  form: null,
  u: [],
  stretches: [],       // per dimension: [{lo, hi, valid, failures}]
  previewCount: 0,     // previews shown so far
  previewSample: -1,   // the snapped sample of the preview on screen
  previewKind: null,   // 'exact' (the design at exactly u) or 'snapped' (the sample's)
  previewQuery: null,  // the u of the exact preview on screen
  properties: null,
  error: null,
  limits: {},          // property -> {min, max} (numbers or undefined)
  reason: null,        // the last reason shown: {check, failure, reason, sample}
  reasonCount: 0,      // reasons shown so far
  download: null,      // the last download: {name, size, format}
  map: null,           // the validity map on screen (/api/map's answer)
  // The transition on screen: {transition, u, valid, failure, frame, frames,
  // t, playing, framesShown, firstCollision (/api/state_graph's), colliding
  // (objects in collision at t), highlighted (objects drawn red)}.
  motion: null,
  motionPlays: 0,      // transitions played to their end so far
  resolution: null,    // the last /api/resolve answer shown (a played collision)
  resolvePlays: 0,     // resolutions shown so far
};
window.fabatlas = state;
// The moving objects on screen (three.js meshes), for the browser test.
state.motionObjects = () => motionMeshes;

const $ = (id) => document.getElementById(id);
// An element built from properties and children (strings become text
// nodes): every string that comes from a design, job or artifact reaches
// the page as text, never as markup (docs/viewer.md, Hostile artifacts).
function node(tag, props = {}, ...children) {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (k === 'dataset') Object.assign(el.dataset, v);
    else el[k] = v;
  }
  el.append(...children);
  return el;
}
// The limits as the API reads them: "volume<=9000,weight:PLA>=3".
function limitsText() {
  const items = [];
  for (const [p, l] of Object.entries(state.limits)) {
    if (Number.isFinite(l.max)) items.push(`${p}<=${l.max}`);
    if (Number.isFinite(l.min)) items.push(`${p}>=${l.min}`);
  }
  return items.join(',');
}
const query = (u) => 'u=' + u.map((v) => String(v)).join(',') +
  (limitsText() ? '&limits=' + encodeURIComponent(limitsText()) : '');

async function api(path) {
  const res = await fetch(path);
  if (!res.ok) throw new Error(`${path}: ${res.status} ${(await res.text()).trim()}`);
  return res;
}
const apiJson = async (path) => (await api(path)).json();

// Routine news; an error stays on the line until the user acts (clearError).
function setStatus(text) {
  if (state.error !== null) return;
  $('status').textContent = text;
}
function clearError() {
  state.error = null;
  $('status').classList.remove('error');
}

// ---------------------------------------------------------------- sliders
const sliders = [];  // {input, number, select, segments, valueLabel, track}

function formatValue(d, v) {
  const dim = state.form.dimensions[d];
  if (dim.kind === 'enumerated') return dim.values[Math.round(v)] ?? String(v);
  if (dim.kind === 'integer') return String(Math.round(v));
  return v.toFixed(2);
}

function buildSliders() {
  const top = $('sliders');
  top.textContent = '';
  // Parameters with a group (from the design file) go under its heading.
  const groups = new Map([['', top]]);
  const hostOf = (group) => {
    if (!groups.has(group)) {
      const fieldset = document.createElement('fieldset');
      fieldset.className = 'group';
      const legend = document.createElement('legend');
      legend.textContent = group;
      fieldset.appendChild(legend);
      top.appendChild(fieldset);
      groups.set(group, fieldset);
    }
    return groups.get(group);
  };
  state.form.dimensions.forEach((d, i) => { if (!d.group) hostOf(''); });
  state.form.dimensions.forEach((dim, d) => {
    const root = hostOf(dim.group ?? '');
    const box = document.createElement('div');
    box.className = 'slider';
    box.append(
      node('div', { className: 'label' }, node('span', { className: 'name' }), node('span', { className: 'value' })),
      node('div', { className: 'row' }, node('div', { className: 'track' }, node('div', { className: 'segments' }),
        node('input', { type: 'range' }))),
      node('div', { className: 'why', hidden: true }));
    box.querySelector('.name').textContent = dim.name;
    if (dim.description) {
      box.querySelector('.name').title = dim.description;
      const hint = document.createElement('div');
      hint.className = 'description';
      hint.textContent = dim.description;
      box.querySelector('.label').after(hint);
    }
    const input = box.querySelector('input[type=range]');
    input.min = dim.lo;
    input.max = dim.hi;
    input.step = dim.kind === 'real' ? 'any' : '1';
    input.dataset.dimension = d;
    input.setAttribute('aria-label', dim.name);
    const track = box.querySelector('.track');
    input.addEventListener('input', () => onSlide(d));
    input.addEventListener('change', () => onSlide(d));
    track.addEventListener('mousemove', (e) => onHover(d, e));
    track.addEventListener('mouseleave', () => { $('tooltip').hidden = true; });
    // A tap (touch or pen) on an invalid stretch shows why under the slider.
    track.addEventListener('pointerdown', (e) => { if (e.pointerType !== 'mouse') onHover(d, e, true); });
    // Beside the slider: a number box, or a dropdown for enumerated values.
    let number = null, select = null;
    if (dim.kind === 'enumerated') {
      select = document.createElement('select');
      select.dataset.dimension = d;
      select.setAttribute('aria-label', dim.name);
      dim.values.forEach((label, i) => select.add(new Option(label, i)));
      select.addEventListener('change', () => setValue(d, Number(select.value)));
      box.querySelector('.row').appendChild(select);
    } else {
      number = document.createElement('input');
      number.type = 'number';
      number.min = dim.lo;
      number.max = dim.hi;
      number.step = dim.kind === 'integer' ? '1' : 'any';
      number.dataset.dimension = d;
      number.setAttribute('aria-label', dim.name + ' value');
      number.addEventListener('change', () => setValue(d, parseFloat(number.value)));
      box.querySelector('.row').appendChild(number);
    }
    root.appendChild(box);
    sliders.push({ input, number, select, segments: box.querySelector('.segments'), valueLabel: box.querySelector('.value'), track,
      why: box.querySelector('.why') });
  });
}

function stretchAt(d, v) {
  return state.stretches[d].find((s) => v >= s.lo && v <= s.hi && (s.valid || (v > s.lo && v < s.hi)))
    ?? state.stretches[d].find((s) => v >= s.lo && v <= s.hi);
}

// The closest value to v inside a valid stretch along d (Fab Forms Sec. 7.2:
// the slider is confined to the valid intervals through the current point).
function clampToValid(d, v) {
  let best = null;
  for (const s of state.stretches[d]) {
    if (!s.valid) continue;
    const c = Math.min(Math.max(v, s.lo), s.hi);
    if (best === null || Math.abs(c - v) < Math.abs(best - v)) best = c;
  }
  return best;
}

function onSlide(d) { setValue(d, parseFloat(sliders[d].input.value)); }

// Sets parameter d to v (from the slider, the number box or the dropdown):
// rounded for integer and enumerated parameters, kept in range and moved to
// the nearest valid interval through the current point.
function setValue(d, v) {
  clearError();
  for (const sl of sliders) sl.why.hidden = true;
  const dim = state.form.dimensions[d];
  if (!Number.isFinite(v)) { drawTracks(); return; }
  v = Math.min(Math.max(v, dim.lo), dim.hi);
  if (dim.kind !== 'real') v = Math.round(v);
  let c = clampToValid(d, v);
  if (c === null) { drawTracks(); return; }
  if (dim.kind !== 'real') c = Math.round(c);
  const input = sliders[d].input;
  if (String(c) !== input.value) input.value = String(c);
  if (c === state.u[d]) { drawTracks(); return; }
  state.u[d] = c;
  sliders[d].valueLabel.textContent = formatValue(d, c);
  requestUpdate();
}

// Why a stretch is invalid, in words (/api/reason), cached per stretch.
const reasons = new Map();
async function reasonFor(d, s, v) {
  const u = state.u.slice();
  u[d] = Math.min(Math.max(v, s.lo), s.hi);
  const key = `${d}:${s.lo}:${s.hi}:${state.u.join(',')}:${limitsText()}`;
  if (!reasons.has(key)) reasons.set(key, apiJson('/api/reason?' + query(u)));
  return reasons.get(key);
}
const reasonWords = (r) => r.sample < 0 ? 'invalid' : `${r.reason} (check: ${r.check}, ${r.failure})`;

function onHover(d, e, tap = false) {
  const rect = sliders[d].segments.getBoundingClientRect();
  const dim = state.form.dimensions[d];
  const t = Math.min(Math.max((e.clientX - rect.left) / rect.width, 0), 1);
  const v = dim.lo + t * (dim.hi - dim.lo);
  const s = stretchAt(d, v);
  const tip = $('tooltip');
  if (!s) { tip.hidden = true; return; }
  const head = `${dim.name} ${formatValue(d, v)}: `;
  tip.textContent = s.valid ? head + 'valid' : head + `not fabricable — ${(s.failures ?? []).join(', ') || 'invalid'}`;
  tip.dataset.failures = s.valid ? '' : (s.failures ?? []).join(',');
  tip.hidden = false;
  tip.style.left = `${e.clientX + 12}px`;
  tip.style.top = `${e.clientY + 12}px`;
  sliders[d].track.title = tip.textContent;
  if (s.valid) { if (tap) sliders[d].why.hidden = true; return; }
  reasonFor(d, s, v).then((r) => {
    state.reason = r;
    state.reasonCount += 1;
    const words = head + 'not fabricable — ' + reasonWords(r);
    if (!tip.hidden && tip.textContent.startsWith(head)) tip.textContent = words;
    sliders[d].track.title = words;
    if (tap) { sliders[d].why.textContent = words; sliders[d].why.hidden = false; }
    offerWhy(r);
  }).catch(showError);
}

function drawTracks() {
  state.form.dimensions.forEach((dim, d) => {
    const { input, segments, valueLabel } = sliders[d];
    segments.textContent = '';
    const span = dim.hi - dim.lo;
    for (const s of state.stretches[d]) {
      const el = document.createElement('div');
      el.className = 'segment ' + (s.valid ? 'valid' : 'invalid') + (s.valid && s.hi === s.lo ? ' point' : '');
      el.style.left = `${((s.lo - dim.lo) / span) * 100}%`;
      el.style.width = `${((s.hi - s.lo) / span) * 100}%`;
      el.dataset.lo = s.lo;
      el.dataset.hi = s.hi;
      if (!s.valid) el.title = `not fabricable: ${(s.failures ?? []).join(', ')}`;
      segments.appendChild(el);
    }
    input.value = String(state.u[d]);
    valueLabel.textContent = formatValue(d, state.u[d]);
    const { number, select } = sliders[d];
    if (number && document.activeElement !== number) number.value = String(Number(state.u[d].toFixed(6)));
    if (select) {
      select.value = String(Math.round(state.u[d]));
      // Values not reachable from here are offered but disabled.
      [...select.options].forEach((o, i) => { o.disabled = clampToValid(d, i) !== i; });
    }
  });
}

// ------------------------------------------------------------- updates
let updating = false;
let pending = false;

function requestUpdate() {
  if (updating) { pending = true; return; }
  updating = true;
  update().catch(showError).finally(() => {
    updating = false;
    if (pending) { pending = false; requestUpdate(); }
  });
}

function showError(e) {
  state.error = String(e.message ?? e);
  $('status').textContent = state.error;
  $('status').classList.add('error');
}

async function update() {
  leaveMotion();
  const u = state.u.slice();
  const [intervals, properties] = await Promise.all([
    apiJson('/api/intervals?' + query(u)),
    apiJson('/api/properties?' + query(u)),
  ]);
  state.stretches = intervals.dimensions;
  state.valid = intervals.valid;
  writeUrl();
  state.properties = properties;
  drawTracks();
  drawReadout(properties);
  await Promise.all([loadPreview(u, properties.sample, true), drawMap(), trade.afterUpdate()]);
}

function drawReadout(p) {
  const rows = [];
  const volume = p.properties.volume;
  if (volume !== undefined) rows.push(['volume', `${(volume / 1000).toFixed(2)} cm³`]);
  for (const [k, v] of Object.entries(p.properties)) if (k !== 'volume') rows.push([k, v.toFixed(2)]);
  const table = $('readout');
  table.textContent = '';
  for (const [k, v] of rows) table.append(node('tr', {}, node('th', {}, k), node('td', {}, v)));
  if (p.materials.length) {
    table.append(node('tr', {}, node('th', {}, 'material'), node('th', {}, 'weight'), node('th', {}, 'cost')));
    for (const m of p.materials)
      table.append(node('tr', { className: 'material' }, node('td', {}, m.name), node('td', {}, `${m.weight_g.toFixed(1)} g`),
        node('td', {}, m.cost.toFixed(2))));
  }
}

// ------------------------------------------------------------- preview
let renderer, scene, camera, controls, modelGroup, fittedSize = 0;
const loader = new GLTFLoader();
const material = new THREE.MeshStandardMaterial({ color: 0xd9b38c, roughness: 0.6, metalness: 0.05 });

function initView() {
  const host = $('preview');
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(host.clientWidth, host.clientHeight);
  host.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  camera = new THREE.PerspectiveCamera(40, host.clientWidth / host.clientHeight, 0.1, 10000);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, 2, 1.5);
  scene.add(sun);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.addEventListener('change', render);
  modelGroup = new THREE.Group();  // glTF is metres, +Y up (artifact/glb.h)
  scene.add(modelGroup);
  window.addEventListener('resize', () => {
    renderer.setSize(host.clientWidth, host.clientHeight);
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    render();
  });
}

function render() { renderer.render(scene, camera); }

function parseGlb(buffer) {
  return new Promise((resolve, reject) => loader.parse(buffer, '', resolve, reject));
}

async function meshFromGlb(buffer) {
  const gltf = await parseGlb(buffer);
  const group = new THREE.Group();
  gltf.scene.traverse((o) => {
    if (o.isMesh) {
      // Exact meshes carry normals split at creases (flat faces, sharp
      // edges); level-set surfaces get smooth ones here.
      if (!o.geometry.attributes.normal) o.geometry.computeVertexNormals();
      // A part an OpenSCAD model coloured (material "part NAME", its
      // color() in baseColorFactor) keeps its colour and opacity.
      const own = o.material;
      if (own?.name?.startsWith('part ')) {
        o.material = material.clone();
        o.material.color.copy(own.color);
        o.material.opacity = own.opacity;
        o.material.transparent = own.transparent;
      } else o.material = material;
      group.add(o.clone());
    }
  });
  return group;
}

function fitCamera(object, cam, ctl) {
  const box = object.isBox3 ? object : new THREE.Box3().setFromObject(object);
  const size = box.getSize(new THREE.Vector3()).length() || 1;
  const centre = box.getCenter(new THREE.Vector3());
  cam.position.copy(centre).add(new THREE.Vector3(0.6, 0.45, 0.9).multiplyScalar(size * 1.1));
  cam.near = size / 100;
  cam.far = size * 100;
  cam.updateProjectionMatrix();
  if (ctl) { ctl.target.copy(centre); ctl.update(); } else cam.lookAt(centre);
}

let previewSeq = 0;
// exact: ask for the design at exactly u; the server answers it when it is
// expected to fit its budget, else the snapped sample's (docs/viewer.md,
// Exact previews). The label under the view says which is shown.
async function loadPreview(u, sample, exact = false) {
  if (!state.form.preview) return;
  if (exact ? query(u) === state.previewQuery : sample === state.previewSample && state.previewKind === 'snapped') return;
  const seq = ++previewSeq;
  const res = await api('/api/preview.glb?' + query(u) + (exact ? '&exact=1' : ''));
  const buffer = await res.arrayBuffer();
  if (seq !== previewSeq) return;
  const kind = res.headers.get('X-Preview');
  const label = () => showPreviewKind(kind, res.headers.get('X-Preview-U'), res.headers.get('X-Preview-Fallback'));
  if (kind === 'snapped' && state.previewKind === 'snapped' && Number(res.headers.get('X-Sample')) === state.previewSample) {
    label();  // the snapped sample on screen already
    return;
  }
  const group = await meshFromGlb(buffer);
  if (seq !== previewSeq) return;
  modelGroup.clear();
  modelGroup.add(group);
  // Refit the camera when the model's size changes a lot (keeps the user's
  // orbit otherwise).
  const size = new THREE.Box3().setFromObject(modelGroup).getSize(new THREE.Vector3()).length();
  if (!fittedSize || size > 1.25 * fittedSize || size < 0.5 * fittedSize) {
    fitCamera(modelGroup, camera, controls);
    fittedSize = size;
  }
  render();
  state.previewSample = Number(res.headers.get('X-Sample'));
  state.previewKind = kind;
  state.previewQuery = kind === 'exact' ? query(u) : null;
  state.previewCount += 1;
  label();
  setStatus(`${kind === 'exact' ? 'exact point' : `sample #${state.previewSample}`} · preview ${(Number(res.headers.get('X-Preview-Seconds')) * 1000).toFixed(0)} ms` +
    ` · cached subtrees ${res.headers.get('X-Cache-Hits')} (${state.form.cache})`);
}

// "exact point" or "nearest sample (values)", from the preview's headers.
function showPreviewKind(kind, shown, fallback) {
  const u = (shown ?? '').split(',').map(Number);
  const values = u.map((v, d) => `${state.form.dimensions[d]?.name} ${formatValue(d, v)}`).join(', ');
  const label = $('preview-kind');
  label.textContent = kind === 'exact' ? 'exact point' : `nearest sample (${values})`;
  label.title = kind === 'exact' ? 'the design evaluated at exactly these values; validity is the form\'s'
    : fallback === 'budget' ? 'an exact preview would take longer than the server\'s budget'
    : fallback === 'failed' ? 'the design could not be evaluated at exactly these values'
    : 'previews snap to the closest valid sample';
}

// ------------------------------------------------------ starting points
async function buildStarts() {
  const host = $('starts');
  host.textContent = '';
  if (!state.form.preview) return;
  const thumb = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  thumb.setSize(120, 120);
  const tScene = new THREE.Scene();
  tScene.background = new THREE.Color(0xf4f4f4);
  tScene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, 2, 1.5);
  tScene.add(sun);
  const tCamera = new THREE.PerspectiveCamera(40, 1, 0.1, 10000);
  for (const [i, start] of state.form.starting_points.entries()) {
    const button = document.createElement('button');
    button.dataset.index = i;
    button.title = start.u.map((v, d) => `${state.form.dimensions[d].name} ${formatValue(d, v)}`).join(', ');
    const img = document.createElement('img');
    img.alt = `starting point ${i + 1}`;
    button.appendChild(img);
    button.addEventListener('click', () => { clearError(); state.u = start.u.slice(); requestUpdate(); });
    host.appendChild(button);
    try {
      const buffer = await (await api('/api/preview.glb?' + query(start.u))).arrayBuffer();
      const group = await meshFromGlb(buffer);
      const holder = new THREE.Group();
      holder.add(group);
      tScene.add(holder);
      fitCamera(holder, tCamera, null);
      thumb.render(tScene, tCamera);
      img.src = thumb.domElement.toDataURL('image/png');
      tScene.remove(holder);
    } catch (e) { img.alt = String(e); }
  }
  thumb.dispose();
}

// ----------------------------------------------------------- validity map
const palette = ['#2b2b2b', '#8a3b3b', '#7a6a2a', '#4a4a7a', '#3b7a5a', '#7a3b7a'];
let mapData = null;

function buildMapControls() {
  const a = $('map-a'), b = $('map-b');
  state.form.dimensions.forEach((dim, d) => {
    a.add(new Option(dim.name, d));
    b.add(new Option(dim.name, d));
  });
  a.value = 0;
  b.value = Math.min(1, state.form.dimensions.length - 1);
  a.addEventListener('change', () => drawMap().catch(showError));
  b.addEventListener('change', () => drawMap().catch(showError));
  $('map').addEventListener('click', onMapClick);
  if (state.form.dimensions.length < 2) $('map').hidden = true;
}

async function drawMap() {
  const a = Number($('map-a').value), b = Number($('map-b').value);
  const canvas = $('map');
  const ctx = canvas.getContext('2d');
  if (a === b || state.form.dimensions.length < 2) {
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    $('map-legend').textContent = 'pick two different parameters';
    mapData = null;
    return;
  }
  const n = 64;
  const m = await apiJson(`/api/map?a=${a}&b=${b}&n=${n}&` + query(state.u));
  mapData = m;
  state.map = m;
  const cw = canvas.width / n, ch = canvas.height / n;
  for (let j = 0; j < n; ++j)
    for (let i = 0; i < n; ++i) {
      const c = m.cells[j * n + i];
      ctx.fillStyle = c < 0 ? '#2f7de1' : palette[c % palette.length];
      ctx.fillRect(i * cw, canvas.height - (j + 1) * ch, Math.ceil(cw), Math.ceil(ch));
    }
  const x = ((state.u[a] - m.a_range[0]) / (m.a_range[1] - m.a_range[0])) * canvas.width;
  const y = canvas.height - ((state.u[b] - m.b_range[0]) / (m.b_range[1] - m.b_range[0])) * canvas.height;
  ctx.strokeStyle = '#fff';
  ctx.lineWidth = 2;
  ctx.strokeRect(x - 4, y - 4, 8, 8);
  const legend = $('map-legend');
  legend.textContent = '';
  legend.append(node('span', { className: 'swatch valid' }), ' valid');
  m.failures.forEach((f, k) => {
    const swatch = node('span', { className: 'swatch' });
    swatch.style.background = palette[k % palette.length];
    legend.append(' ', swatch, ' ', f);
  });
}

function onMapClick(e) {
  if (!mapData) return;
  clearError();
  const canvas = $('map');
  const rect = canvas.getBoundingClientRect();
  const n = mapData.n;
  const i = Math.min(n - 1, Math.floor(((e.clientX - rect.left) / rect.width) * n));
  const j = Math.min(n - 1, Math.floor(((rect.bottom - e.clientY) / rect.height) * n));
  const cell = mapData.cells[j * n + i];
  const u = state.u.slice();
  u[mapData.a] = mapData.a_range[0] + ((i + 0.5) / n) * (mapData.a_range[1] - mapData.a_range[0]);
  u[mapData.b] = mapData.b_range[0] + ((j + 0.5) / n) * (mapData.b_range[1] - mapData.b_range[0]);
  if (cell >= 0) {
    setStatus(`not fabricable there: ${mapData.failures[cell]}`);
    // A reconfigurable's collision: play the invalid sample next to the
    // click, to see when and where it collides.
    if (state.form.transitions.length && ['collision', 'too_little_clearance'].includes(mapData.failures[cell]))
      apiJson('/api/reason?' + query(u)).then((r) => {
        state.reason = r;
        offerWhy(r);
        if (r.sample >= 0) playTransition(null, r.sample_u, `invalid sample #${r.sample}`);
      }).catch(showError);
    return;
  }
  state.u = u;
  requestUpdate();
}

// ------------------------------------------------------------ transitions
// Reconfigurables (Sec. 5): /api/state_graph evaluates the design at exactly
// a point with its checks; the page moves each object's mesh (body frame,
// mm, z up) by the poses it sends, in a group that turns mm / z up into the
// preview's metres / +Y up (as artifact/glb.h's node transform does).
let motionData = null, motionGroup = null, motionMeshes = [], whereBox = null, motionTimer = null;
const collidingMaterial = new THREE.MeshStandardMaterial({ color: 0xd62828, roughness: 0.5, metalness: 0.05 });
const PLAY_SECONDS = 2.5;

function buildTransitions() {
  if (!state.form.transitions?.length) return;
  $('motion-panel').hidden = false;
  for (const t of state.form.transitions) {
    const b = document.createElement('button');
    b.textContent = `Play ${t.name}`;
    b.title = `${t.from} → ${t.to}, at the current design`;
    b.dataset.transition = t.name;
    b.addEventListener('click', () => playTransition(t.name, state.properties?.u ?? state.u, 'this design'));
    $('transitions').appendChild(b);
  }
  $('motion-t').addEventListener('input', () => {
    if (!motionData) return;
    stopPlaying();
    const tr = currentTransition();
    const t = parseFloat($('motion-t').value);
    let k = 0;
    tr.times.forEach((x, i) => { if (Math.abs(x - t) < Math.abs(tr.times[k] - t)) k = i; });
    showFrame(k);
  });
  $('motion-back').addEventListener('click', leaveMotion);
  $('resolve-hint').addEventListener('click', () => showResolution().catch(showError));
  $('resolve-apply').addEventListener('click', () => {
    const r = state.resolution?.resolution;
    if (!r?.resolved) return;
    leaveMotion();
    clearError();
    state.u = r.u.slice();
    requestUpdate();
  });
  $('motion-why').addEventListener('click', () => {
    const r = state.reason;
    if (r && r.sample >= 0) playTransition(null, r.sample_u, `invalid sample #${r.sample}`);
  });
}

// Back to the preview (the button, or any change of the point).
function leaveMotion() {
  if (!state.motion) return;
  stopPlaying();
  if (motionGroup) motionGroup.visible = false;
  modelGroup.visible = true;
  $('motion-back').hidden = true;
  hideResolution();
  state.motion = null;
  render();
}

// After a reason in words: a collision can be played.
function offerWhy(r) {
  const b = $('motion-why');
  if (!state.form.transitions?.length || r.sample < 0 || r.check !== 'collision_free') { b.hidden = true; return; }
  b.textContent = `Play invalid sample #${r.sample} (${r.failure})`;
  b.hidden = false;
}

const currentTransition = () => motionData.transitions.find((t) => t.name === state.motion.transition);

function stopPlaying() {
  if (motionTimer !== null) cancelAnimationFrame(motionTimer);
  motionTimer = null;
  if (state.motion) state.motion.playing = false;
}

function buildMotionMeshes(data) {
  if (!motionGroup) {
    motionGroup = new THREE.Group();
    motionGroup.rotation.x = -Math.PI / 2;  // z up -> +Y up
    motionGroup.scale.setScalar(1 / 1000);  // mm -> m
    scene.add(motionGroup);
  }
  motionGroup.clear();
  motionMeshes = data.objects.map((o) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(o.positions, 3));
    g.setIndex(o.triangles);
    g.computeVertexNormals();
    const m = new THREE.Mesh(g, material);
    m.name = o.name;
    m.matrixAutoUpdate = false;
    motionGroup.add(m);
    return m;
  });
  whereBox = new THREE.Box3Helper(new THREE.Box3(), 0xd62828);
  whereBox.visible = false;
  motionGroup.add(whereBox);
}

// Frame k of the transition on screen: poses, colliding objects drawn red,
// the collision's box (where) drawn, time shown.
function showFrame(k) {
  const tr = currentTransition();
  const t = tr.times[k];
  tr.poses[k].forEach((p, i) => {
    motionMeshes[i].matrix.set(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], 0, 0, 0, 1);
    motionMeshes[i].matrixWorldNeedsUpdate = true;
  });
  const hits = tr.collisions.filter((c) => c.t_begin <= t && t <= c.t_end);
  const colliding = [...new Set(hits.flatMap((c) => c.objects))];
  for (const m of motionMeshes) m.material = colliding.includes(m.name) ? collidingMaterial : material;
  whereBox.visible = hits.length > 0;
  if (hits.length) {
    const w = hits[0].where;
    whereBox.box.set(new THREE.Vector3(...w.min), new THREE.Vector3(...w.max));
  }
  Object.assign(state.motion, { frame: k, t, colliding,
    highlighted: motionMeshes.filter((m) => m.material === collidingMaterial).map((m) => m.name) });
  state.motion.framesShown += 1;
  $('motion-t').value = String(t);
  $('motion-time').textContent = `t = ${t.toFixed(4)}`;
  render();
}

// /api/state_graph answers of the last 4 points played (each is one
// evaluation with checks on the server, and megabytes): replays are instant.
const stateGraphs = new Map();
function stateGraphAt(u) {
  const key = u.map((v) => String(v)).join(',');
  if (!stateGraphs.has(key)) {
    const answer = apiJson('/api/state_graph?frames=61&u=' + key);
    answer.catch(() => stateGraphs.delete(key));
    stateGraphs.set(key, answer);
    if (stateGraphs.size > 4) stateGraphs.delete(stateGraphs.keys().next().value);
  }
  return stateGraphs.get(key);
}

// Plays transition `name` (null: the one that collides first, else the
// first) of the design at exactly u, then rests at its first colliding time.
async function playTransition(name, u, label) {
  clearError();
  stopPlaying();
  hideResolution();
  setStatus(`evaluating the state graph at ${label}…`);
  const data = await stateGraphAt(u).catch((e) => { showError(e); return null; });
  if (!data) return;
  if (!data.objects.length) {
    showError(new Error(`${label}: no geometry to play (${data.failure}: ${data.reason})`));
    return;
  }
  motionData = data;
  const tr = data.transitions.find((t) => t.name === name)
    ?? data.transitions.find((t) => t.name === data.first_collision?.transition) ?? data.transitions[0];
  const first = tr.collisions.length ? data.first_collision?.transition === tr.name ? data.first_collision
    : { transition: tr.name, t: tr.collisions[0].t_begin, t_end: tr.collisions[0].t_end, objects: tr.collisions[0].objects } : null;
  buildMotionMeshes(data);
  modelGroup.visible = false;
  motionGroup.visible = true;
  $('motion-back').hidden = false;
  state.motion = { transition: tr.name, u: data.u, label, valid: data.valid, failure: data.failure ?? null,
    reason: data.reason ?? null, frame: 0, frames: tr.times.length, t: 0, playing: true, framesShown: 0,
    firstCollision: first, colliding: [], highlighted: [] };
  const info = $('motion-info');
  info.classList.toggle('collision', first !== null);
  info.textContent = `${tr.name} (${tr.from} → ${tr.to}) at ${label}: ` + (first
    ? `first collision at t = ${first.t.toFixed(4)} (until ${first.t_end.toFixed(4)}): '${first.objects[0]}' and '${first.objects[1]}'`
    : data.collisions_checked ? 'no collision' : 'collisions not checked (the design has no collision_free check)') +
    (!data.valid && !first ? ` — not fabricable here: ${data.reason} (check: ${data.check}, ${data.failure})` : '');
  // Fit to the objects in their first pose (not the hidden collision box).
  motionGroup.updateMatrixWorld(true);
  const bounds = new THREE.Box3();
  for (const m of motionMeshes) bounds.expandByObject(m);
  fitCamera(bounds, camera, controls);
  const start = performance.now();
  const last = tr.times.length - 1;
  let k = -1;
  const step = () => {
    // Frames follow wall time, but advance by 1 to 6 per screen refresh: a
    // slow machine plays slower instead of jumping to the end.
    const due = Math.floor(((performance.now() - start) / (PLAY_SECONDS * 1000)) * last);
    k = Math.min(last, Math.max(k + 1, Math.min(due, k + 6)));
    showFrame(k);
    if (k < last) { motionTimer = requestAnimationFrame(step); return; }
    motionTimer = null;
    state.motion.playing = false;
    // Rest at the first colliding time: the collision in view, parts red.
    if (first) showFrame(tr.times.indexOf(first.t));
    $('resolve-hint').hidden = first === null;
    state.motionPlays += 1;
    setStatus(info.textContent);
  };
  motionTimer = requestAnimationFrame(step);
}

// ------------------------------------------------ collision resolution
// Reconfigurables Secs. 6.4–6.6 (/api/resolve at the point played): an
// arrow on the selected object (the second of the colliding pair) along the
// spacetime contact normal, drawn at the centre of the interval's box, the
// hint in the parameters, and the design resolved automatically, which
// "Use the resolved design" moves to.
let hintArrows = [];
function hideResolution() {
  for (const a of hintArrows) a.removeFromParent();
  hintArrows = [];
  $('resolve-hint').hidden = true;
  $('resolve-apply').hidden = true;
  $('resolve-info').hidden = true;
  state.resolution = null;
  state.hintArrows = [];
}

async function showResolution() {
  if (!state.motion) return;
  const u = state.motion.u;
  setStatus('resolving the collisions (contact normals, hints, automatic resolution)…');
  $('resolve-hint').disabled = true;
  const r = await apiJson('/api/resolve?u=' + u.map((v) => String(v)).join(',')).finally(() => { $('resolve-hint').disabled = false; });
  if (!state.motion || state.motion.u !== u) return;  // left or moved on meanwhile
  state.resolution = r;
  for (const a of hintArrows) a.removeFromParent();
  const size = new THREE.Box3();
  for (const m of motionMeshes) size.expandByObject(m);
  const length = 0.25 * size.getSize(new THREE.Vector3()).length() * 1000;  // mm (the group's units)
  hintArrows = r.intervals.map((i) => {
    const arrow = new THREE.ArrowHelper(new THREE.Vector3(...i.normal).normalize(), new THREE.Vector3(...i.at),
      length, 0xffc300, 0.25 * length, 0.12 * length);
    arrow.name = 'hint:' + i.object;
    motionGroup.add(arrow);
    return arrow;
  });
  state.hintArrows = r.intervals.map((i) => ({ object: i.object, at: i.at, normal: i.normal }));
  const f = (v) => (v >= 0 ? '+' : '') + v.toPrecision(4);
  const lines = r.intervals.map((i) => `move '${i.object}' along (${i.normal.map((x) => x.toFixed(2)).join(', ')})` +
    ` away from '${i.objects[0]}' (t in [${i.t_begin.toFixed(4)}, ${i.t_end.toFixed(4)}])`);
  for (const p of r.pairs)
    lines.push(`'${p.objects[0]}' and '${p.objects[1]}': ` +
      (Object.keys(p.step).length ? Object.entries(p.step).map(([n, v]) => `${n} ${f(v)}`).join(', ') : 'no step lowers the collision'));
  const res = r.resolution;
  if (res) lines.push(res.resolved
    ? `resolved: ${Object.entries(res.edit).map(([n, v]) => `${n} ${f(v)}`).join(', ')} (the checks pass there)`
    : `not resolved within the parameters (${res.failure})`);
  const info = $('resolve-info');
  info.textContent = '';
  lines.forEach((line, k) => info.append(...(k ? [node('br'), line] : [line])));
  info.hidden = false;
  $('resolve-apply').hidden = !res?.resolved;
  state.resolvePlays = (state.resolvePlays ?? 0) + 1;
  setStatus(lines[lines.length - 1]);
  render();
}

// ------------------------------------------------- the point in the URL
// ?radius=15&wall=6&limits=volume<=9000 : open the URL, get the same design.
function writeUrl() {
  const params = new URLSearchParams();
  state.form.dimensions.forEach((dim, d) => params.set(dim.name, dim.kind === 'enumerated'
    ? dim.values[Math.round(state.u[d])] : String(state.u[d])));
  if (limitsText()) params.set('limits', limitsText());
  history.replaceState(null, '', '?' + params.toString());
}

// The point named by the URL, over `fallback` (values it does not name).
function readUrl(fallback) {
  const params = new URLSearchParams(location.search);
  const u = fallback.slice();
  state.form.dimensions.forEach((dim, d) => {
    const text = params.get(dim.name);
    if (text === null) return;
    const v = dim.kind === 'enumerated' ? dim.values.indexOf(text) : Number(text);
    if (v >= 0 && Number.isFinite(v) && v >= dim.lo && v <= dim.hi) u[d] = v;
    else showError(new Error(`URL: ${dim.name}=${text} is not a value of ${dim.name}`));
  });
  for (const item of (params.get('limits') ?? '').split(',').filter(Boolean)) {
    const m = item.match(/^(.+?)(<=|>=)(.+)$/);
    if (!m || !Number.isFinite(Number(m[3]))) continue;
    const l = state.limits[m[1]] ??= {};
    l[m[2] === '<=' ? 'max' : 'min'] = Number(m[3]);
  }
  return u;
}

// ------------------------------------------------------------- download
async function download(format) {
  const res = await api(`/api/export?format=${format}&` + query(state.u));
  const bytes = new Uint8Array(await res.arrayBuffer());
  const name = (res.headers.get('Content-Disposition') ?? '').match(/filename="([^"]+)"/)?.[1] ?? `design.${format}`;
  state.download = { name, format, size: bytes.length };
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([bytes], { type: res.headers.get('Content-Type') }));
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 60000);
  setStatus(`downloaded ${name} (${(bytes.length / 1024).toFixed(0)} KiB, ${res.headers.get('X-Triangles')} triangles, voxel ${Number(res.headers.get('X-Voxel-Size')).toFixed(3)} mm)`);
}

function buildDownloads() {
  for (const format of ['stl', '3mf']) {
    const b = $('download-' + format);
    b.addEventListener('click', () => {
      b.disabled = true;
      download(format).catch(showError).finally(() => { b.disabled = false; });
    });
  }
}

// ---------------------------------------------------------------- presets
// OpenSCAD's parameter-set JSON: {"parameterSets": {name: {param: "value"}},
// "fileFormatVersion": "1"}; kept in this browser's localStorage per design.
const presetKey = () => `fabatlas:presets:${state.form.name}`;
function loadPresets() {
  try { return JSON.parse(localStorage.getItem(presetKey())) ?? { parameterSets: {}, fileFormatVersion: '1' }; }
  catch { return { parameterSets: {}, fileFormatVersion: '1' }; }
}
function savePresets(p) { localStorage.setItem(presetKey(), JSON.stringify(p)); drawPresets(); }
function drawPresets() {
  const select = $('preset');
  select.textContent = '';
  select.add(new Option('— presets —', ''));
  for (const name of Object.keys(loadPresets().parameterSets)) select.add(new Option(name, name));
}
function presetOf() {
  const set = {};
  state.form.dimensions.forEach((dim, d) => {
    set[dim.name] = dim.kind === 'enumerated' ? dim.values[Math.round(state.u[d])] : String(state.u[d]);
  });
  return set;
}
function applyPreset(set) {
  clearError();
  const u = state.u.slice();
  state.form.dimensions.forEach((dim, d) => {
    if (!(dim.name in set)) return;
    const text = String(set[dim.name]);
    const v = dim.kind === 'enumerated' ? dim.values.indexOf(text) : Number(text);
    if (v >= 0 && Number.isFinite(v)) u[d] = Math.min(Math.max(v, dim.lo), dim.hi);
  });
  state.u = u;
  requestUpdate();
}
function buildPresets() {
  drawPresets();
  $('preset').addEventListener('change', () => {
    const set = loadPresets().parameterSets[$('preset').value];
    if (set) applyPreset(set);
  });
  $('preset-save').addEventListener('click', () => {
    const name = $('preset-name').value.trim();
    if (!name) { setStatus('name the preset first'); return; }
    const p = loadPresets();
    p.parameterSets[name] = presetOf();
    savePresets(p);
    $('preset').value = name;
  });
  $('preset-export').addEventListener('click', () => {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(new Blob([JSON.stringify(loadPresets(), null, 2)], { type: 'application/json' }));
    a.download = `${state.form.name}.json`;
    a.click();
  });
  $('preset-import').addEventListener('change', async () => {
    const file = $('preset-import').files[0];
    if (!file) return;
    try {
      const sets = JSON.parse(await file.text()).parameterSets;
      if (!sets || typeof sets !== 'object') throw new Error('no parameterSets');
      const p = loadPresets();
      Object.assign(p.parameterSets, sets);
      savePresets(p);
      setStatus(`loaded ${Object.keys(sets).length} presets from ${file.name}`);
    } catch (e) { showError(new Error(`${file.name}: not an OpenSCAD parameter-set file (${e.message})`)); }
  });
}

// ----------------------------------------------------------------- limits
// Bounds on stored properties and, per material, weight (g) and cost.
function buildLimits() {
  const host = $('limits');
  host.textContent = '';
  const names = [...(state.form.properties ?? [])];
  if (names.includes('volume'))
    for (const m of state.form.materials) names.push(`weight:${m.name}`, `cost:${m.name}`);
  for (const p of names) {
    const row = document.createElement('div');
    row.className = 'limit';
    row.append(node('span', { className: 'name' }),
      node('input', { type: 'number', step: 'any', placeholder: 'min', dataset: { bound: 'min' } }), ' ',
      node('input', { type: 'number', step: 'any', placeholder: 'max', dataset: { bound: 'max' } }));
    row.querySelector('.name').textContent = p.replace(/^(weight|cost):(.*)$/, '$1 in $2') +
      (p === 'volume' ? ' (mm³)' : p.startsWith('weight:') ? ' (g)' : p.startsWith('bbox') ? ' (mm)' : '');
    for (const input of row.querySelectorAll('input')) {
      input.dataset.property = p;
      input.setAttribute('aria-label', `${p} ${input.dataset.bound}`);
      const l = state.limits[p];
      if (l && Number.isFinite(l[input.dataset.bound])) input.value = l[input.dataset.bound];
      input.addEventListener('change', () => setLimit(p, input.dataset.bound, input.value));
    }
    host.appendChild(row);
  }
}

// A changed limit: if the current point leaves the valid region, it moves to
// the closest sample that meets every limit.
async function setLimit(property, bound, text) {
  clearError();
  const l = state.limits[property] ??= {};
  l[bound] = text === '' ? undefined : Number(text);
  if (!Number.isFinite(l.min) && !Number.isFinite(l.max)) delete state.limits[property];
  reasons.clear();
  try {
    const at = await apiJson('/api/intervals?' + query(state.u));
    if (!at.valid) {
      const snap = await apiJson('/api/snap?' + query(state.u));
      state.u = snap.sample_u.slice();
    }
    requestUpdate();
  } catch (e) { showError(e); }
}

// ------------------------------------------------- objectives, trade-offs
// "Best for…" and the Pareto plot live in optimise.js.
const trade = installOptimise({
  state, $, apiJson, limitsText, formatValue, showError, setStatus, clearError,
  moveTo: (u) => { clearError(); state.u = u.slice(); requestUpdate(); },
  preview: (u, sample) => loadPreview(u, sample),
  restorePreview: () => { if (state.properties) loadPreview(state.u, state.properties.sample, true).catch(showError); },
});

// ------------------------------------------------------------------ start
async function main() {
  state.form = await apiJson('/api/form');
  $('title').textContent = `${state.form.name} — fabatlas customiser`;
  document.title = $('title').textContent;
  const start = state.form.starting_points[0];
  state.u = readUrl(start ? start.u.slice() : state.form.dimensions.map((d) => d.default ?? (d.lo + d.hi) / 2));
  buildSliders();
  buildMapControls();
  buildDownloads();
  buildPresets();
  buildLimits();
  trade.build();
  initView();
  buildTransitions();
  await update();
  state.ready = true;
  buildStarts().catch(showError);
}

main().catch(showError);
