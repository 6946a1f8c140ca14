import * as THREE from 'three';
import { state, $, node } from './state.js';
import { apiJson, setStatus, clearError, showError } from './api.js';
import { requestUpdate } from './update.js';
import { scene, camera, controls, modelGroup, material, render, fitCamera } from './preview.js';

// ------------------------------------------------------------ transitions
// Reconfigurables (Sec. 5): /api/state_graph evaluates the design at exactly
// a point with its checks; the page moves each object's mesh (body frame,
// mm, z up) by the poses it sends, in a group that turns mm / z up into the
// preview's metres / +Y up (as artifact/glb.h's node transform does).
let motionData = null, motionGroup = null, motionMeshes = [], whereBox = null, motionTimer = null;
const collidingMaterial = new THREE.MeshStandardMaterial({ color: 0xd62828, roughness: 0.5, metalness: 0.05 });
const PLAY_SECONDS = 2.5;
// The moving objects on screen (three.js meshes), for the browser test.
state.motionObjects = () => motionMeshes;

export function buildTransitions() {
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
export function leaveMotion() {
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
export function offerWhy(r) {
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
export async function playTransition(name, u, label) {
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
