// One slider per exposed parameter (Fab Forms Sec. 7.2), its track painted
// with the valid and invalid stretches through the current point, a number
// box or dropdown beside it, and why a stretch is invalid in words.
import { state, $, node } from './state.js';
import { limitsText, query, apiJson, clearError, showError } from './api.js';
import { requestUpdate } from './update.js';
import { offerWhy } from './motion.js';
import { fixedRow } from './fixed.js';

const sliders = [];  // {input, number, select, segments, valueLabel, track}

export function formatValue(d, v) {
  const dim = state.form.dimensions[d];
  if (dim.kind === 'enumerated') return dim.values[Math.round(v)] ?? String(v);
  if (dim.kind === 'integer') return String(Math.round(v));
  return v.toFixed(2);
}

export function buildSliders() {
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
  // The parameters the form does not sample, read-only, in their groups.
  for (const f of state.form.fixed ?? []) hostOf(f.group ?? '').appendChild(fixedRow(f));
}

function stretchAt(d, v) {
  return state.stretches[d].find((s) => v >= s.lo && v <= s.hi && (s.valid || (v > s.lo && v < s.hi)))
    ?? state.stretches[d].find((s) => v >= s.lo && v <= s.hi);
}

// The closest value to v inside a valid stretch along d (Fab Forms Sec. 7.2:
// the slider is confined to the valid intervals through the current point).
export function clampToValid(d, v) {
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
export function setValue(d, v) {
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
export const reasons = new Map();
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

export function drawTracks() {
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
