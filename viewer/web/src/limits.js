import { state, $, node } from './state.js';
import { query, apiJson, clearError, showError } from './api.js';
import { reasons } from './sliders.js';
import { requestUpdate } from './update.js';

// ----------------------------------------------------------------- limits
// Bounds on stored properties and, per material, weight (g) and cost.
export function buildLimits() {
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
