// One update of the page after the point or the limits change: intervals,
// properties, preview, map and trade-offs, one at a time (a change during an
// update runs once more after it).
import { state, $, node } from './state.js';
import { query, apiJson, showError } from './api.js';
import { drawTracks } from './sliders.js';
import { loadPreview } from './preview.js';
import { drawMap } from './map.js';
import { leaveMotion } from './motion.js';
import { writeUrl } from './url.js';
import { trade } from './trade.js';

let updating = false;
let pending = false;

export function requestUpdate() {
  if (updating) { pending = true; return; }
  updating = true;
  update().catch(showError).finally(() => {
    updating = false;
    if (pending) { pending = false; requestUpdate(); }
  });
}

export async function update() {
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
  const space = state.form.dimensions.length > 0;
  await Promise.all([loadPreview(u, properties.sample, true), space && drawMap(), space && trade.afterUpdate()]);
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
