import { state, $ } from './state.js';
import { limitsText, apiJson, setStatus, clearError, showError } from './api.js';
import { formatValue } from './sliders.js';
import { requestUpdate } from './update.js';
import { loadPreview } from './preview.js';
import { installOptimise } from './optimise.js';

// ------------------------------------------------- objectives, trade-offs
// "Best for…" and the Pareto plot live in optimise.js.
export const trade = installOptimise({
  state, $, apiJson, limitsText, formatValue, showError, setStatus, clearError,
  moveTo: (u) => { clearError(); state.u = u.slice(); requestUpdate(); },
  preview: (u, sample) => loadPreview(u, sample),
  restorePreview: () => { if (state.properties) loadPreview(state.u, state.properties.sample, true).catch(showError); },
});
