// A model with nothing to customise (issue 32): openscad-testing-data's
// 3D/features/union-coincident-test.scad has no Customizer annotation, so
// `fabatlas run MODEL.scad` precomputes it as a form of no dimensions, one
// sample (fixture viewer_one_sample_run: a real coordinator and worker).
// The customiser of that artifact:
//   1. shows no slider and no validity map, and the model's one number `e`
//      read-only with its value as the model writes it (0.000 is the literal,
//      OpenSCAD prints it 0) and the model's comment as its description;
//   2. previews the model (a mesh of the two crossed bars) with no error;
//   3. downloads an STL whose enclosed volume is OpenSCAD 2021.01's: its
//      STL of this model encloses 9.000 mm³ (two 1 x 5 x 1 bars crossing
//      in a unit cube).
// Keeps a screenshot in $FABATLAS_TEST_OUTPUT/viewer_one_sample.png.
import { check, env, openPage, runBrowserTest, statusOk } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';

// The volume a binary STL encloses (divergence theorem over its triangles).
function stlVolume(buffer) {
  const count = buffer.readUInt32LE(80);
  let volume = 0;
  for (let t = 0; t < count; ++t) {
    const at = 84 + t * 50 + 12, v = [];
    for (let i = 0; i < 9; ++i) v.push(buffer.readFloatLE(at + 4 * i));
    volume += (v[0] * (v[4] * v[8] - v[5] * v[7]) - v[1] * (v[3] * v[8] - v[5] * v[6]) + v[2] * (v[3] * v[7] - v[4] * v[6])) / 6;
  }
  return volume;
}

await runBrowserTest(env.FABATLAS_ONE_SAMPLE_RUN, async ({ server, browser }) => {
  const { page, errors } = await openPage(browser, server.url);
  const form = await (await page.request.get(server.url + 'api/form')).json();
  check(form.dimensions.length === 0 && form.samples === 1, `a form of no dimensions and one sample: ${form.dimensions.length}, ${form.samples}`);
  const sliders = await page.locator('input[type=range][data-dimension]').count();
  check(sliders === 0, `no slider on the page: ${sliders}`);
  const mapShown = await page.evaluate(() => {
    const m = document.querySelector('#map');
    return m !== null && m.offsetParent !== null;
  });
  check(!mapShown, 'no validity map for a form with nothing to vary');
  const rows = await page.evaluate(() => [...document.querySelectorAll('.fixed-param')].map((r) => ({
    name: r.querySelector('.name').textContent, value: r.querySelector('.value').textContent,
    description: r.querySelector('.description')?.textContent ?? '', inputs: r.querySelectorAll('input, select, textarea').length })));
  check(rows.length === 1 && rows[0].name === 'e' && rows[0].value === '0' && rows[0].inputs === 0,
    `the model's one number, read-only: ${JSON.stringify(rows)}`);
  check(rows[0]?.description === 'Causes a CGAL assertion in CGALEvaluator::process()', `its comment: ${rows[0]?.description}`);
  const shown = await page.evaluate(() => ({ count: window.fabatlas.previewCount, sample: window.fabatlas.previewSample }));
  check(shown.count >= 1 && shown.sample === 0, `the preview shows the one sample: ${JSON.stringify(shown)}`);
  const label = await page.locator('#preview-kind').textContent();
  check(label === 'the model (nothing to customise)', `the preview says what it shows: ${label}`);
  const stl = await page.request.get(server.url + 'api/export?u=&format=stl');
  check(stl.ok(), `STL download: ${stl.status()}`);
  const volume = stlVolume(await stl.body());
  check(Math.abs(volume - 9) < 1e-3, `the download encloses OpenSCAD's 9.000 mm³: ${volume.toFixed(4)}`);
  await statusOk(page, 'one sample');
  await page.screenshot({ path: `${out}/viewer_one_sample.png`, fullPage: true });
  check(errors.length === 0, `no page or API error: ${errors.join('; ')}`);
});
