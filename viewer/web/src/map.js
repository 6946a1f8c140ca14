// The 2-D validity map over two chosen parameters through the current
// point (/api/map); a click moves there, or says why it is not fabricable.
import { state, $, node } from './state.js';
import { query, apiJson, setStatus, clearError, showError } from './api.js';
import { requestUpdate } from './update.js';
import { offerWhy, playTransition } from './motion.js';

const palette = ['#2b2b2b', '#8a3b3b', '#7a6a2a', '#4a4a7a', '#3b7a5a', '#7a3b7a'];
let mapData = null;

export function buildMapControls() {
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

export async function drawMap() {
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
