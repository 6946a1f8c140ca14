import { state } from './state.js';
import { limitsText, showError } from './api.js';

// ------------------------------------------------- the point in the URL
// ?radius=15&wall=6&limits=volume<=9000 : open the URL, get the same design.
export function writeUrl() {
  const params = new URLSearchParams();
  state.form.dimensions.forEach((dim, d) => params.set(dim.name, dim.kind === 'enumerated'
    ? dim.values[Math.round(state.u[d])] : String(state.u[d])));
  if (limitsText()) params.set('limits', limitsText());
  history.replaceState(null, '', '?' + params.toString());
}

// The point named by the URL, over `fallback` (values it does not name).
export function readUrl(fallback) {
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
