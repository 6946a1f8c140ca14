// Objectives and trade-offs in the customiser (docs/viewer.md "Objectives
// and trade-offs"): a "Best for…" control asks /api/optimise for the best
// valid design (Schulz et al. 2017) and moves the sliders there, holding the
// parameters ticked at their current values; the trade-off plot draws
// /api/pareto's front of two quantities (Schulz et al. 2018) beside the
// validity map: hovering a point previews that design, a click moves the
// sliders there, the current design is the orange ring. Every element is
// built with createElement / textContent: names and values from the API stay
// text.

// ctx: {state, $, apiJson, limitsText, formatValue, moveTo(u), preview(u, sample),
//       restorePreview(), showError(e), setStatus(text), clearError()}
export function installOptimise(ctx) {
  const { state, $ } = ctx;
  state.optimise = null;   // the last /api/optimise answer
  state.pareto = null;     // the front on screen (/api/pareto's answer)
  state.paretoHover = -1;  // sample id of the front point under the pointer
  state.bestCount = 0;     // "best for" answers applied so far
  // Where a front point is drawn, in CSS pixels from the plot's top-left
  // corner (null when not on screen): for the browser test.
  state.paretoXY = (sample) => {
    const p = state.pareto?.points.find((q) => q.sample === sample);
    if (!p || !box) return null;
    const canvas = $('pareto'), rect = canvas.getBoundingClientRect();
    return { x: (box.X(p.a) * rect.width) / canvas.width, y: (box.Y(p.b) * rect.height) / canvas.height };
  };
  state.paretoRing = null;  // where the current design's ring is drawn (canvas pixels), or null

  const limitsQuery = () => (ctx.limitsText() ? '&limits=' + encodeURIComponent(ctx.limitsText()) : '');

  // Quantities: recorded properties, weight / cost per material, parameters.
  function quantities() {
    const names = [...(state.form.properties ?? [])];
    if (names.includes('volume'))
      for (const m of state.form.materials) names.push(`weight:${m.name}`, `cost:${m.name}`);
    for (const d of state.form.dimensions) if (!names.includes(d.name)) names.push(d.name);
    return names;
  }
  function label(sense, name) {
    const m = /^(weight|cost):(.*)$/.exec(name);
    if (m && m[1] === 'weight') return sense === 'min' ? `lightest in ${m[2]}` : `heaviest in ${m[2]}`;
    if (m) return sense === 'min' ? `cheapest in ${m[2]}` : `dearest in ${m[2]}`;
    return `${sense === 'min' ? 'smallest' : 'largest'} ${name}`;
  }
  function option(select, value, text) {
    const o = document.createElement('option');
    o.value = value;
    o.textContent = text;
    select.appendChild(o);
  }

  // ------------------------------------------------------------ best for
  function buildBest() {
    const host = $('best-for');
    host.textContent = '';
    const select = document.createElement('select');
    select.id = 'best-objective';
    select.setAttribute('aria-label', 'objective');
    for (const name of quantities()) for (const sense of ['min', 'max']) option(select, `${sense}:${name}`, label(sense, name));
    const first = quantities().find((n) => n.startsWith('weight:')) ?? quantities()[0];
    if (first) select.value = `min:${first}`;
    const go = document.createElement('button');
    go.id = 'best-go';
    go.textContent = 'Go';
    go.title = 'move the sliders to the best valid design (under your limits, with the ticked parameters held)';
    host.append(select, go);
    const holds = document.createElement('div');
    holds.className = 'holds';
    holds.append('hold: ');
    state.form.dimensions.forEach((dim, d) => {
      const l = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.dataset.dimension = d;
      box.className = 'best-hold';
      l.append(box, ' ' + dim.name + ' ');
      holds.appendChild(l);
    });
    host.appendChild(holds);
    const result = document.createElement('p');
    result.id = 'best-result';
    result.className = 'hint';
    host.appendChild(result);
    go.addEventListener('click', () => best(select.value).catch(ctx.showError));
  }

  async function best(choice) {
    ctx.clearError();
    const sense = choice.slice(0, 3), name = choice.slice(4);
    const held = [...document.querySelectorAll('.best-hold')].filter((b) => b.checked).map((b) => Number(b.dataset.dimension));
    const hold = held.map((d) => `${state.form.dimensions[d].name}=${state.u[d]}`).join(',');
    const r = await ctx.apiJson(`/api/optimise?${sense}=${encodeURIComponent(name)}` +
      (hold ? '&hold=' + encodeURIComponent(hold) : '') + limitsQuery());
    state.optimise = r;
    const out = $('best-result');
    if (!r.found) { out.textContent = r.reason; return; }
    const where = r.u.map((v, d) => `${state.form.dimensions[d].name} ${ctx.formatValue(d, v)}`).join(', ');
    out.textContent = `${label(sense, name)}: ${name} ${Number(r.objective.toPrecision(6))} at ${where}` +
      (r.interpolated ? ' (interpolated between samples)' : ` (sample #${r.sample})`);
    state.bestCount += 1;
    ctx.moveTo(r.u);
  }

  // ------------------------------------------------------------ trade-off
  const pad = { left: 34, right: 8, top: 8, bottom: 22 };
  let box = null;  // plot geometry of the front on screen

  function buildPareto() {
    const a = $('pareto-a'), b = $('pareto-b');
    for (const sel of [a, b]) {
      sel.textContent = '';
      for (const name of quantities()) for (const sense of ['min', 'max']) option(sel, `${sense}:${name}`, `${sense} ${name}`);
    }
    const names = quantities();
    a.value = `min:${names.includes('volume') ? 'volume' : names[0]}`;
    b.value = `max:${state.form.dimensions[0].name}`;
    for (const sel of [a, b]) sel.addEventListener('change', () => drawPareto(true).catch(ctx.showError));
    const canvas = $('pareto');
    canvas.addEventListener('mousemove', onParetoHover);
    canvas.addEventListener('mouseleave', () => {
      if (state.paretoHover < 0) return;
      state.paretoHover = -1;
      ctx.restorePreview();
      draw();
    });
    canvas.addEventListener('click', onParetoClick);
  }

  let loadedKey = '';
  async function drawPareto(force = false) {
    const axes = `${$('pareto-a').value},${$('pareto-b').value}`;
    const key = axes + '|' + ctx.limitsText();
    if (force || key !== loadedKey) {
      loadedKey = key;
      if ($('pareto-a').value.slice(4) === $('pareto-b').value.slice(4)) {
        state.pareto = null;
        $('pareto-legend').textContent = 'pick two different quantities';
        draw();
        return;
      }
      state.pareto = await ctx.apiJson(`/api/pareto?axes=${encodeURIComponent(axes)}&dominated=400` + limitsQuery());
    }
    draw();
  }

  // The current design's value on an axis: a parameter's coordinate, a
  // recorded property or a material's weight / cost of the previewed sample.
  function currentValue(name) {
    const d = state.form.dimensions.findIndex((dim) => dim.name === name);
    const p = state.properties;
    if (p && name in p.properties) return p.properties[name];
    const m = /^(weight|cost):(.*)$/.exec(name);
    if (p && m) {
      const mat = p.materials.find((x) => x.name === m[2]);
      return mat ? (m[1] === 'weight' ? mat.weight_g : mat.cost) : undefined;
    }
    return d >= 0 ? (p ? p.u[d] : state.u[d]) : undefined;  // the previewed sample's
  }

  function draw() {
    const canvas = $('pareto');
    const g = canvas.getContext('2d');
    g.clearRect(0, 0, canvas.width, canvas.height);
    const f = state.pareto;
    if (!f || !f.points.length) { box = null; state.paretoRing = null; if (f) $('pareto-legend').textContent = 'no valid sample records both'; return; }
    const all = f.points.concat(f.dominated);
    let [alo, ahi, blo, bhi] = [Infinity, -Infinity, Infinity, -Infinity];
    for (const p of all) { alo = Math.min(alo, p.a); ahi = Math.max(ahi, p.a); blo = Math.min(blo, p.b); bhi = Math.max(bhi, p.b); }
    if (!(ahi > alo)) { alo -= 0.5; ahi += 0.5; }
    if (!(bhi > blo)) { blo -= 0.5; bhi += 0.5; }
    const W = canvas.width - pad.left - pad.right, H = canvas.height - pad.top - pad.bottom;
    const X = (a) => pad.left + ((a - alo) / (ahi - alo)) * W;
    const Y = (b) => pad.top + H - ((b - blo) / (bhi - blo)) * H;
    box = { X, Y };
    g.strokeStyle = '#999';
    g.strokeRect(pad.left, pad.top, W, H);
    g.fillStyle = '#555';
    g.font = '10px system-ui, sans-serif';
    g.textAlign = 'left';
    g.fillText(String(Number(alo.toPrecision(3))), pad.left, canvas.height - 8);
    g.textAlign = 'right';
    g.fillText(String(Number(ahi.toPrecision(3))), pad.left + W, canvas.height - 8);
    g.fillText(String(Number(bhi.toPrecision(3))), pad.left - 3, pad.top + 8);
    g.fillText(String(Number(blo.toPrecision(3))), pad.left - 3, pad.top + H);
    g.fillStyle = '#c8c8c8';
    for (const p of f.dominated) g.fillRect(X(p.a) - 1, Y(p.b) - 1, 2, 2);
    g.strokeStyle = '#2f7de1';
    g.lineWidth = 1.5;
    g.beginPath();
    f.points.forEach((p, k) => {
      if (k === 0) g.moveTo(X(p.a), Y(p.b));
      else { g.lineTo(X(p.a), Y(f.points[k - 1].b)); g.lineTo(X(p.a), Y(p.b)); }
    });
    g.stroke();
    for (const p of f.points) {
      g.fillStyle = p.sample === state.paretoHover ? '#1a4f96' : '#2f7de1';
      const r = p.sample === state.paretoHover ? 4 : 2.5;
      g.fillRect(X(p.a) - r, Y(p.b) - r, 2 * r, 2 * r);
    }
    const ca = currentValue(f.a), cb = currentValue(f.b);
    state.paretoRing = null;
    if (Number.isFinite(ca) && Number.isFinite(cb)) {
      state.paretoRing = { x: X(ca), y: Y(cb), a: ca, b: cb };
      g.strokeStyle = '#e07b00';
      g.lineWidth = 2;
      g.beginPath();
      g.arc(X(ca), Y(cb), 6, 0, 2 * Math.PI);
      g.stroke();
    }
    $('pareto-legend').textContent = `x: ${f.a_maximise ? 'max' : 'min'} ${f.a}, y: ${f.b_maximise ? 'max' : 'min'} ${f.b} · ` +
      `${f.points.length} of ${f.candidates} valid samples on the front · ring: this design`;
  }

  function pointAt(e) {
    if (!box || !state.pareto) return null;
    const canvas = $('pareto');
    const rect = canvas.getBoundingClientRect();
    const x = ((e.clientX - rect.left) / rect.width) * canvas.width, y = ((e.clientY - rect.top) / rect.height) * canvas.height;
    let best = null, bestD = 8 * 8;
    for (const p of state.pareto.points) {
      const d2 = (box.X(p.a) - x) ** 2 + (box.Y(p.b) - y) ** 2;
      if (d2 <= bestD) { best = p; bestD = d2; }
    }
    return best;
  }

  function onParetoHover(e) {
    const p = pointAt(e);
    const sample = p ? p.sample : -1;
    if (sample === state.paretoHover) return;
    state.paretoHover = sample;
    draw();
    const canvas = $('pareto');
    if (p) {
      canvas.title = `${state.pareto.a} ${Number(p.a.toPrecision(6))}, ${state.pareto.b} ${Number(p.b.toPrecision(6))} (sample #${p.sample}); click to move there`;
      ctx.preview(p.u, p.sample).catch(ctx.showError);
    } else {
      canvas.title = 'the Pareto front: hover previews a design, click moves there';
      ctx.restorePreview();
    }
  }

  function onParetoClick(e) {
    const p = pointAt(e);
    if (!p) return;
    state.paretoHover = -1;
    ctx.setStatus(`moved to the front's sample #${p.sample}`);
    ctx.moveTo(p.u);
  }

  return {
    build() { buildBest(); buildPareto(); },
    // After every update of the design: the front follows the limits, the
    // ring the current design.
    afterUpdate() { return drawPareto(); },
  };
}
