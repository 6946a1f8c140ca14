// Talking to `fabatlas serve` (docs/viewer.md): the point and the limits as
// the API reads them, fetches that fail loudly, the status line.
import { state, $ } from './state.js';

// The limits as the API reads them: "volume<=9000,weight:PLA>=3".
export function limitsText() {
  const items = [];
  for (const [p, l] of Object.entries(state.limits)) {
    if (Number.isFinite(l.max)) items.push(`${p}<=${l.max}`);
    if (Number.isFinite(l.min)) items.push(`${p}>=${l.min}`);
  }
  return items.join(',');
}
export function query(u) {
  return 'u=' + u.map((v) => String(v)).join(',') +
    (limitsText() ? '&limits=' + encodeURIComponent(limitsText()) : '');
}

export async function api(path) {
  const res = await fetch(path);
  if (!res.ok) throw new Error(`${path}: ${res.status} ${(await res.text()).trim()}`);
  return res;
}
export async function apiJson(path) { return (await api(path)).json(); }

// Routine news; an error stays on the line until the user acts (clearError).
export function setStatus(text) {
  if (state.error !== null) return;
  $('status').textContent = text;
}
export function clearError() {
  state.error = null;
  $('status').classList.remove('error');
}
export function showError(e) {
  state.error = String(e.message ?? e);
  $('status').textContent = state.error;
  $('status').classList.add('error');
}
