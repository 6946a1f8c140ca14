// The page's shared state (read by the browser tests under tests/viewer as
// window.fabatlas), the element lookup and the one way the page builds
// elements from strings.

// State shared with tests (tests/viewer/browser_test.mjs reads it).
export const state = {
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

export function $(id) { return document.getElementById(id); }
// An element built from properties and children (strings become text
// nodes): every string that comes from a design, job or artifact reaches
// the page as text, never as markup (docs/viewer.md, Hostile artifacts).
export function node(tag, props = {}, ...children) {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (k === 'dataset') Object.assign(el.dataset, v);
    else el[k] = v;
  }
  el.append(...children);
  return el;
}
