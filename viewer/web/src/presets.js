import { state, $ } from './state.js';
import { setStatus, clearError, showError } from './api.js';
import { requestUpdate } from './update.js';

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
export function buildPresets() {
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
