// Fixed parameters in the customiser (issue 32): a real `fabatlas serve` of
// the 18 Customizer parameters of tests/scad/data/organiser.scad on a box
// (tests/viewer/data/fixed_box.scad) imported by
// `fabatlas import-scad --expose columns,rows` and sampled on its bootstrap
// grid (fixture viewer_organiser_run). Every Customizer parameter the import
// kept fixed (but [Hidden] ones) is on the page, read-only (no input in its row), with the
// model's value as the model writes it, in its Customizer group, with its
// description; the page's list equals /api/params's fixed parameters, and
// /api/params's exposed ones are the sliders. Exit status 0 = pass.
import { check, env, openPage, runBrowserTest, statusOk } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';
// The model's values (organiser.scad), as OpenSCAD literals.
const want = {
  width: ['80', 'Size', 'Outer width (mm)'], depth: ['60', 'Size', 'Outer depth (mm)'],
  divider_ratio: ['0.8', 'Compartments', 'Divider height as a fraction of the height'],
  lip: ['1.5', 'Finish', 'Stacking lip height (mm)'], notches: ['true', 'Finish', 'Finger notch in every divider'],
  label_text: ['"tools"', 'Finish', 'Text on the label'],
};

await runBrowserTest(env.FABATLAS_ORGANISER_RUN, async ({ server, browser }) => {
  const { page, errors } = await openPage(browser, server.url);
  const rows = await page.evaluate(() => [...document.querySelectorAll('.fixed-param')].map((r) => ({
    name: r.querySelector('.name').textContent, value: r.querySelector('.value').textContent,
    group: r.closest('fieldset')?.querySelector('legend').textContent ?? '',
    description: r.querySelector('.description')?.textContent ?? '', inputs: r.querySelectorAll('input, select, textarea').length,
    why: r.title })));
  const params = await (await page.request.get(server.url + 'api/params')).json();
  const fixed = params.parameters.filter((p) => !p.exposed);
  check(rows.length === 13 && rows.length === fixed.length, `every fixed parameter shown: ${rows.length} rows, ${fixed.length} in /api/params`);
  // The page groups rows under their Customizer groups; /api/params lists them in file order.
  const pageList = rows.map((r) => `${r.name}=${r.value}`).sort(), apiList = fixed.map((f) => `${f.name}=${f.value}`).sort();
  check(JSON.stringify(pageList) === JSON.stringify(apiList), `the page's fixed values are /api/params's: ${pageList}`);
  check(rows.every((r) => r.inputs === 0), 'fixed rows are read-only (no input)');
  for (const [name, [value, group, description]] of Object.entries(want)) {
    const r = rows.find((x) => x.name === name);
    check(r && r.value === value && r.group === group && r.description === description,
      `${name}: ${value} in '${group}' described '${description}': ${JSON.stringify(r)}`);
  }
  check(rows.find((x) => x.name === 'lip')?.why === "fixed at the model's value: not named by --expose (a number in group 'Finish')",
    'the row says why it is fixed (its tooltip)');
  const exposed = params.parameters.filter((p) => p.exposed).map((p) => `${p.name}:${p.kind}:${p.min}:${p.max}:${p.step}`);
  check(JSON.stringify(exposed) === JSON.stringify(['columns:integer:1:6:1', 'rows:integer:1:6:1']), `exposed in /api/params: ${exposed}`);
  check(params.groups.join('|') === 'Compartments|Size|Walls|Finish', `groups in order of first appearance: ${params.groups}`);
  const sliders = await page.evaluate(() => [...document.querySelectorAll('input[type=range][data-dimension]')].map((i) => i.getAttribute('aria-label')));
  check(JSON.stringify(sliders) === JSON.stringify(['columns', 'rows']), `sliders: ${sliders}`);
  await statusOk(page, 'organiser');
  await page.screenshot({ path: `${out}/viewer_fixed.png`, fullPage: true });
  check(errors.length === 0, `no page or API error: ${errors.join('; ')}`);
});
