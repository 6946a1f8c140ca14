// Fixed parameters (docs/viewer.md): the model's parameters the form does not
// sample (e.g. OpenSCAD Customizer parameters `import-scad` kept at the
// model's values), shown read-only with their values in their groups, so a
// person sees the whole model. Names, values and descriptions stay text.
import { node } from './state.js';

// One read-only row: name, value, description, and why it is fixed (title).
export function fixedRow(f) {
  const row = node('div', { className: 'fixed-param', dataset: { name: f.name } },
    node('div', { className: 'label' }, node('span', { className: 'name' }, f.name), ' ',
      node('output', { className: 'value' }, f.value), ' ', node('span', { className: 'badge' }, 'fixed')));
  if (f.description) row.append(node('div', { className: 'description' }, f.description));
  row.title = f.why ? `fixed at the model's value: ${f.why}` : 'fixed at the model\'s value';
  return row;
}
