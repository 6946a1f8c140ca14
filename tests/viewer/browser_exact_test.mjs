// Exact previews in the customiser (headless Chromium on the tube run,
// tests/viewer/data/tube_wall_2d.yaml, whose samples have no wall between
// 7.4 and 9.7 mm).
//   1. With a budget nothing on this host exceeds (`serve --exact-budget-ms
//      600000`), dragging the wall slider between samples shows the design at
//      exactly the slider's point: the label says "exact point", the point the
//      server says it showed is the page's, and the preview's pixels change
//      between two points that snap to the same sample (which the snapped
//      preview could not do).
//   2. With a budget of 0 (a second serve) the same point shows the snapped
//      sample, labelled "nearest sample (radius …, wall …)".
// No answer of /api may be a 4xx/5xx (browser_support.mjs, openPage).
import { check, drag, env, openPage, runBrowserTest, settle, startServer, statusOk } from './browser_support.mjs';

const canvasPixels = (page) => page.evaluate(() => document.querySelector('#preview canvas').toDataURL());
// Quiet, with the preview of the current point (exact or not) on screen.
async function previewOfCurrentPoint(page) {
  await settle(page);
  await page.waitForFunction(() => {
    const s = window.fabatlas;
    return s.previewKind === 'snapped' || s.previewQuery === 'u=' + s.u.map(String).join(',');
  }, null, { timeout: 60000 });
}
const shown = (page) => page.evaluate(() => ({ u: window.fabatlas.u.slice(), kind: window.fabatlas.previewKind,
  sample: window.fabatlas.previewSample, label: document.querySelector('#preview-kind').textContent }));

await runBrowserTest(env.FABATLAS_VIEWER_RUN, async ({ server, browser }) => {
  const { page, errors } = await openPage(browser, server.url + '?radius=20.6&wall=9.7');
  await previewOfCurrentPoint(page);
  const start = await shown(page);
  const pixelsStart = await canvasPixels(page);

  // 1. The wall slider between samples, at two points that snap to the
  //    sample at wall 7.4: 8.0, then 8.35.
  const points = [];
  for (const wall of [8.0, 8.35]) {
    await drag(page, 1, wall);
    await previewOfCurrentPoint(page);
    const at = await shown(page);
    const snap = await (await page.request.get(server.url + 'api/snap?u=' + at.u.join(','))).json();
    const res = await page.request.get(server.url + 'api/preview.glb?exact=1&u=' + at.u.join(','));
    points.push({ ...at, pixels: await canvasPixels(page), snapWall: snap.sample_u[1] });
    check(at.u[1] > 7.6 && at.u[1] < 9.5, `the wall slider rests between samples: ${at.u[1].toFixed(3)}`);
    check(Math.abs(snap.sample_u[1] - at.u[1]) > 0.1, `the point's snapped sample has another wall (${snap.sample_u[1]})`);
    check(at.kind === 'exact' && at.label === 'exact point', `the label says "${at.label}" (${at.kind})`);
    check(res.headers()['x-preview'] === 'exact' && res.headers()['x-preview-u'].split(',').map(Number).every((v, d) => v === at.u[d]),
      `the server shows exactly the page's point: ${res.headers()['x-preview-u']} (page ${at.u.join(',')})`);
  }
  check(points[0].pixels !== pixelsStart, 'the preview changed from the sample at wall 9.7');
  check(points[0].sample === points[1].sample, `both points snap to one sample (#${points[0].sample}, #${points[1].sample})`);
  check(points[0].pixels !== points[1].pixels,
    `the preview follows the exact point (walls ${points[0].u[1].toFixed(2)} and ${points[1].u[1].toFixed(2)}; ` +
    `snapped samples #${points[0].sample} and #${points[1].sample})`);
  check(start.label.length > 0, `a label is shown at the start: "${start.label}"`);
  await statusOk(page, 'exact previews');
  check(errors.length === 0, `no page errors or failed API answers: ${JSON.stringify(errors)}`);

  // 2. Budget 0: the same point shows the nearest sample, labelled so.
  const snapped = await startServer(env.FABATLAS_VIEWER_RUN, ['--exact-budget-ms', '0']);
  try {
    const other = await openPage(browser, snapped.url + `?radius=20.6&wall=${points[1].u[1]}`);
    await previewOfCurrentPoint(other.page);
    const at = await shown(other.page);
    const snap = await (await other.page.request.get(snapped.url + 'api/snap?u=' + at.u.join(','))).json();
    check(at.kind === 'snapped', `budget 0: the preview is the snapped sample's (${at.kind})`);
    check(at.label.startsWith('nearest sample (radius ') && at.label.includes(`wall ${snap.sample_u[1].toFixed(2)}`),
      `budget 0: the label names the sample shown: "${at.label}"`);
    check(other.errors.length === 0, `budget 0: no page errors or failed API answers: ${JSON.stringify(other.errors)}`);
  } finally {
    snapped.child.kill('SIGTERM');
  }
}, ['--exact-budget-ms', '600000']);
