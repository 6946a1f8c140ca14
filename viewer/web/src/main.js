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
// Each panel lives in its own module; this one starts the page.
import { state, $ } from './state.js';
import { apiJson, showError } from './api.js';
import { buildSliders } from './sliders.js';
import { update } from './update.js';
import { initView } from './preview.js';
import { buildStarts } from './starts.js';
import { buildMapControls } from './map.js';
import { buildTransitions } from './motion.js';
import { readUrl } from './url.js';
import { buildDownloads } from './downloads.js';
import { buildPresets } from './presets.js';
import { buildLimits } from './limits.js';
import { trade } from './trade.js';

// ------------------------------------------------------------------ start
async function main() {
  state.form = await apiJson('/api/form');
  $('title').textContent = `${state.form.name} — fabatlas customiser`;
  document.title = $('title').textContent;
  const start = state.form.starting_points[0];
  state.u = readUrl(start ? start.u.slice() : state.form.dimensions.map((d) => d.default ?? (d.lo + d.hi) / 2));
  buildSliders();
  buildDownloads();
  // A form of no dimensions (a model with nothing exposed) is one design:
  // no presets, limits, map, trade-offs or starting points to move between.
  const space = state.form.dimensions.length > 0;
  for (const panel of document.querySelectorAll('.space-only')) panel.hidden = !space;
  if (space) {
    buildMapControls();
    buildPresets();
    buildLimits();
    trade.build();
  }
  initView();
  buildTransitions();
  await update();
  state.ready = true;
  if (space) buildStarts().catch(showError);
}

main().catch(showError);