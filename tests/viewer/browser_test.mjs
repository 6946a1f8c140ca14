// The web customiser in headless Chromium (playwright-core, Debian's
// chromium): load the page that `fabatlas serve` serves for a real run's
// artifact, drag a slider and see the preview change, drag a slider into an
// invalid stretch and see it come to rest in a valid interval, hover an
// invalid stretch and see its failure type and its reason in words (hover
// and tap), the status line free of errors and the validity map drawn as the
// tube's closed form says (valid where wall >= 1 + 0.01 radius^2 and
// radius - wall >= 2), map clicks and axis selectors, starting-point clicks,
// the number box, the URL round trip, a volume limit shrinking the wall
// slider's valid stretch, an error on the status line, and STL / 3MF
// downloads whose bytes are a closed mesh of the tube's analytic volume
// pi (r^2 - (r - w)^2) 20 at the chosen point. Keeps a screenshot in
// $FABATLAS_TEST_OUTPUT/viewer_browser.png. Exit status 0 = pass.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { check, clickMap, drag, env, openPage, runBrowserTest, settle, statusOk, xOf } from './browser_support.mjs';

const run = env.FABATLAS_VIEWER_RUN;
const out = env.FABATLAS_TEST_OUTPUT ?? '.';

const truly = (r, w) => w >= 1 + 0.01 * r * r && r - w >= 2;
const tubeVolume = (r, w) => Math.PI * (r * r - (r - w) * (r - w)) * 20;

// The colour of the validity map at parameter values (a, b) of its axes.
async function mapColour(page, a, b) {
  return page.evaluate(([a, b]) => {
    const c = document.querySelector('#map');
    const m = window.fabatlas.map;
    const x = Math.floor(((a - m.a_range[0]) / (m.a_range[1] - m.a_range[0])) * c.width);
    const y = Math.floor(c.height - ((b - m.b_range[0]) / (m.b_range[1] - m.b_range[0])) * c.height);
    const p = c.getContext('2d').getImageData(x, y, 1, 1).data;
    return (p[0] === 0x2f && p[1] === 0x7d && p[2] === 0xe1) ? 'valid' : 'invalid';
  }, [a, b]);
}

// Binary STL facts: triangles, edges not shared by two triangles, volume.
function stlFacts(buf) {
  const n = buf.readUInt32LE(80);
  const edges = new Map();
  let volume = 0;
  for (let t = 0; t < n; ++t) {
    const o = 84 + 50 * t + 12;
    const v = [0, 1, 2].map((k) => [0, 1, 2].map((i) => buf.readFloatLE(o + 12 * k + 4 * i)));
    const [a, b, c] = v;
    volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
    for (let k = 0; k < 3; ++k) {
      const p = v[k].join(','), q = v[(k + 1) % 3].join(',');
      const key = p < q ? p + '|' + q : q + '|' + p;
      edges.set(key, (edges.get(key) ?? 0) + 1);
    }
  }
  let open = 0;
  for (const c of edges.values()) open += c !== 2;
  return { n, open, volume, size: buf.length, expected: 84 + 50 * n };
}

const canvasPixels = (page) => page.evaluate(() => document.querySelector('#preview canvas').toDataURL());

await runBrowserTest(run, async ({ server, browser }) => {
    const { page, errors } = await openPage(browser, server.url);
    check(await page.evaluate(() => window.fabatlas.form.dimensions.length) === 2, 'two sliders for radius and wall');
    // Descriptions and groups from the design file (tube_wall_2d_design.yaml).
    const groups = await page.evaluate(() => [...document.querySelectorAll('fieldset.group')].map((f) =>
      [f.querySelector('legend').textContent, f.querySelector('.slider .name').textContent, f.querySelector('.description').textContent]));
    check(JSON.stringify(groups) === JSON.stringify([['Size', 'radius', 'outer radius of the tube (mm)'], ['Strength', 'wall', 'wall thickness (mm)']]),
      `groups and descriptions from the design file: ${JSON.stringify(groups)}`);

    // 1. Drag the radius slider across its valid interval: the preview changes.
    const before = await page.evaluate(() => ({ u: window.fabatlas.u.slice(), sample: window.fabatlas.previewSample }));
    const pixelsBefore = await canvasPixels(page);
    const radiusValid = await page.evaluate(() => window.fabatlas.stretches[0].filter((s) => s.valid));
    const interval = radiusValid.find((s) => s.lo <= before.u[0] && before.u[0] <= s.hi);
    const farEnd = before.u[0] - interval.lo > interval.hi - before.u[0] ? interval.lo : interval.hi;
    await drag(page, 0, before.u[0] + 0.9 * (farEnd - before.u[0]));
    await settle(page);
    const after = await page.evaluate(() => ({ u: window.fabatlas.u.slice(), sample: window.fabatlas.previewSample, count: window.fabatlas.previewCount }));
    check(Math.abs(after.u[0] - before.u[0]) > 0.5 * Math.abs(farEnd - before.u[0]), `radius moved from ${before.u[0].toFixed(2)} to ${after.u[0].toFixed(2)}`);
    check(after.sample !== before.sample, `preview sample changed (${before.sample} -> ${after.sample})`);
    check(await canvasPixels(page) !== pixelsBefore, 'preview pixels changed');

    // 2. Drag the wall slider deep into an invalid stretch: it rests in a valid interval.
    const stretches = await page.evaluate(() => window.fabatlas.stretches[1]);
    const invalid = stretches.find((s) => !s.valid);
    check(invalid !== undefined, 'the wall slider shows an invalid stretch');
    if (invalid) {
      const into = (invalid.lo + invalid.hi) / 2;
      await drag(page, 1, into);
      await settle(page);
      const rest = await page.evaluate(() => ({
        u: window.fabatlas.u.slice(),
        input: parseFloat(document.querySelector('input[type=range][data-dimension="1"]').value),
      }));
      const now = await (await page.request.get(server.url + 'api/intervals?u=' + rest.u.join(','))).json();
      // The range input stores its value as a decimal string; allow the same
      // 1e-9-of-a-range tolerance the server applies to coordinates on a cut.
      const dim = await page.evaluate(() => window.fabatlas.form.dimensions[1]);
      const eps = 1e-9 * (dim.hi - dim.lo);
      const inValid = now.dimensions[1].some((s) => s.valid && s.lo - eps <= rest.input && rest.input <= s.hi + eps);
      check(now.valid, `the point after the drag is valid (${rest.u.map((v) => v.toFixed(3)).join(', ')})`);
      check(inValid, `the wall slider rests at ${rest.input.toFixed(3)}, inside a valid interval`);
      check(!(rest.input > invalid.lo + eps && rest.input < invalid.hi - eps), `not inside the invalid stretch (${invalid.lo.toFixed(2)}, ${invalid.hi.toFixed(2)})`);

      // 3. Hover the invalid stretch: the tooltip names the failure type.
      const p = await xOf(page, 1, into);
      await page.mouse.move(p.x, p.y);
      const tip = await page.locator('#tooltip').textContent();
      check(invalid.failures.length > 0 && invalid.failures.every((f) => tip.includes(f)), `hover shows why: "${tip}"`);
    }

    await statusOk(page, 'after the drags');

    // 4. Reasons in words: hovering an invalid stretch of the radius slider
    // (the wall bound of the design's constraint) says which constraint, in
    // the design's words; a tap shows it under the slider.
    {
      const u = await page.evaluate(() => window.fabatlas.u.slice());
      const bad = (await page.evaluate(() => window.fabatlas.stretches[0])).filter((s) => !s.valid).pop();
      const v = (bad.lo + bad.hi) / 2;
      const p = await xOf(page, 0, v);
      await page.mouse.move(p.x, p.y - 3);
      await page.mouse.move(p.x + 1, p.y);
      await page.waitForFunction(() => document.querySelector('#tooltip').textContent.includes('check:'), null, { timeout: 30000 });
      const tip = await page.locator('#tooltip').textContent();
      // Which constraint the truth at (v, wall) breaks:
      const wallBound = u[1] < 1 + 0.01 * v * v, boreBound = v - u[1] < 2;
      check((!wallBound || tip.includes("'wall >= 1 + 0.01 * radius^2'")) && (wallBound || !boreBound || tip.includes('bore')),
        `hover says why in words: "${tip}"`);
      await page.locator('.slider .track').first().dispatchEvent('pointerdown', { pointerType: 'touch', clientX: p.x, clientY: p.y, bubbles: true });
      await page.waitForFunction(() => { const w = document.querySelector('.slider .why'); return !w.hidden && w.textContent.includes('check:'); }, null, { timeout: 30000 });
      check(true, 'a tap shows the reason under the slider: ' + await page.locator('.slider .why').first().textContent());
      await settle(page);
    }

    // 5. The validity map is drawn as the closed form says, its clicks jump,
    // its axis selectors swap the axes.
    await page.waitForFunction(() => window.fabatlas.map !== null, null, { timeout: 30000 });
    for (const [r, w] of [[15.5, 6.5], [20, 8], [29, 1], [8, 7.5], [25, 3]]) {
      const want = truly(r, w) ? 'valid' : 'invalid';
      check(await mapColour(page, r, w) === want, `map at radius ${r}, wall ${w} drawn ${want}`);
    }
    {
      await clickMap(page, 20, 8);
      await page.waitForFunction(() => Math.abs(window.fabatlas.u[0] - 20) < 0.5 && Math.abs(window.fabatlas.u[1] - 8) < 0.2, null, { timeout: 30000 });
      await settle(page);
      check(true, 'a click on a valid map cell jumps there: ' + (await page.evaluate(() => window.fabatlas.u.map((v) => v.toFixed(2)).join(', '))));
      const before = await page.evaluate(() => window.fabatlas.u.slice());
      await clickMap(page, 29, 1);
      await page.waitForFunction(() => document.querySelector('#status').textContent.startsWith('not fabricable there'), null, { timeout: 30000 })
        .catch((e) => page.evaluate(() => [document.querySelector('#status').textContent, window.fabatlas.error, window.fabatlas.u])
          .then((st) => { throw new Error(e.message + ' status: ' + JSON.stringify(st)); }));
      const after = await page.evaluate(() => window.fabatlas.u.slice());
      check(after[0] === before[0] && after[1] === before[1], 'a click on an invalid cell does not move the point');
      check((await page.locator('#status').textContent()).includes('unsat_constraints'), 'and says why on the status line');
      await page.selectOption('#map-a', '1');
      await page.selectOption('#map-b', '0');
      await page.waitForFunction(() => window.fabatlas.map.a === 1 && window.fabatlas.map.b === 0, null, { timeout: 30000 });
      check(await mapColour(page, 6.5, 15.5) === 'valid' && await mapColour(page, 1, 29) === 'invalid', 'axis selectors swap the map axes');
      await page.selectOption('#map-a', '0');
      await page.selectOption('#map-b', '1');
    }

    // 6. Starting points: thumbnails drawn; a click jumps to one.
    await page.waitForFunction(() => [...document.querySelectorAll('#starts img')].some((i) => i.src.startsWith('data:image/png')), null, { timeout: 60000 });
    check(await page.locator('#starts button').count() >= 1, 'starting-point thumbnails');
    {
      const start = await page.evaluate(() => window.fabatlas.form.starting_points.at(-1).u);
      await page.locator('#starts button').last().click();
      await page.waitForFunction((s) => window.fabatlas.u.every((v, d) => v === s[d]), start, { timeout: 30000 });
      await settle(page);
      check(true, `a starting-point click jumps to (${start.map((v) => v.toFixed(2)).join(', ')})`);
    }

    // 7. The number box sets a value; the URL carries the point and opens the
    // same design in a new page.
    {
      await page.fill('input[type=number][data-dimension="0"]', '15');
      await page.press('input[type=number][data-dimension="0"]', 'Enter');
      await page.waitForFunction(() => window.fabatlas.u[0] === 15, null, { timeout: 30000 });
      await page.fill('input[type=number][data-dimension="1"]', '6');
      await page.press('input[type=number][data-dimension="1"]', 'Enter');
      await page.waitForFunction(() => window.fabatlas.u[1] === 6, null, { timeout: 30000 });
      await settle(page);
      const url = page.url();
      check(/[?&]radius=15(&|$)/.test(url) && /[?&]wall=6(&|$)/.test(url), `the URL carries the point: ${url}`);
      const again = await browser.newPage({ viewport: { width: 1200, height: 760 } });
      await again.goto(url);
      await again.waitForFunction(() => window.fabatlas.ready && window.fabatlas.previewCount >= 1, null, { timeout: 60000 });
      await settle(again);
      const a = await page.evaluate(() => ({ u: window.fabatlas.u, s: window.fabatlas.previewSample }));
      const b = await again.evaluate(() => ({ u: window.fabatlas.u, s: window.fabatlas.previewSample }));
      check(JSON.stringify(a) === JSON.stringify(b), `the URL opens the same design (${JSON.stringify(b)})`);
      // A URL with a value that is not one: the error line says so.
      await again.goto(server.url + '?radius=abc&wall=6');
      await again.waitForFunction(() => window.fabatlas.error !== null, null, { timeout: 60000 });
      const err = await again.locator('#status').textContent();
      check(err.includes('radius=abc') && await again.locator('#status.error').count() === 1, `the error line: "${err}"`);
      await again.close();
    }

    // 8. Downloads: the STL and 3MF bytes are a closed mesh of the tube at
    // exactly (15, 6).
    {
      const [stl] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click('#download-stl')]);
      const f = stlFacts(fs.readFileSync(await stl.path()));
      const exact = tubeVolume(15, 6);
      check(stl.suggestedFilename() === 'tube_wall_2d-radius=15_wall=6.stl', `STL named ${stl.suggestedFilename()}`);
      check(f.size === f.expected && f.n > 1000 && f.open === 0, `STL is binary and closed (${f.n} triangles, ${f.open} open edges)`);
      check(Math.abs(f.volume - exact) < 0.01 * exact, `STL volume ${f.volume.toFixed(0)} vs analytic ${exact.toFixed(0)} mm^3`);
      const [three] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click('#download-3mf')]);
      const file = await three.path();
      const py = `import sys, zipfile, xml.etree.ElementTree as ET
z = zipfile.ZipFile(sys.argv[1]); assert z.testzip() is None
ns = {'m': 'http://schemas.microsoft.com/3dmanufacturing/core/2015/02'}
root = ET.fromstring(z.read('3D/3dmodel.model'))
v = [tuple(float(e.get(k)) for k in 'xyz') for e in root.iterfind('.//m:vertex', ns)]
edges = {}; vol = 0.0
for t in root.iterfind('.//m:triangle', ns):
    i = [int(t.get(k)) for k in ('v1', 'v2', 'v3')]; a, b, c = (v[k] for k in i)
    vol += (a[0]*(b[1]*c[2]-b[2]*c[1]) - a[1]*(b[0]*c[2]-b[2]*c[0]) + a[2]*(b[0]*c[1]-b[1]*c[0])) / 6
    for e in ((i[0], i[1]), (i[1], i[2]), (i[2], i[0])): edges[e] = edges.get(e, 0) + 1
print(sum(1 for (p, q), k in edges.items() if k != 1 or edges.get((q, p)) != 1), vol, root.get('unit'))`;
      const [open, volume, unit] = execFileSync('python3', ['-c', py, file]).toString().trim().split(' ');
      check(three.suggestedFilename().endsWith('.3mf') && open === '0' && unit === 'millimeter',
        `3MF opens in Python's zipfile, closed (${open} bad edges), in ${unit}`);
      check(Math.abs(Number(volume) - exact) < 0.01 * exact, `3MF volume ${Number(volume).toFixed(0)} vs analytic ${exact.toFixed(0)} mm^3`);
    }

    // 9. A volume limit shrinks the wall slider's valid stretch at radius 15
    // to walls whose volume meets it: V(15, 8.5) caps the wall at 8.5, between
    // the run's samples at walls 7.4 (within) and 9.7 (beyond), far above the
    // smallest valid wall (3.25), so the stretch must end in [7.4, 8.5 + 0.3].
    // The point starts at wall 11, beyond the limit, so it has to move into
    // it (to the closest sample that meets it, on another radius); then the
    // stretch is read back at radius 15.
    {
      const validHi = () => page.evaluate(() => Math.max(...window.fabatlas.stretches[1].filter((s) => s.valid).map((s) => s.hi)));
      const type = async (dimension, value) => {
        await page.fill(`input[type=number][data-dimension="${dimension}"]`, String(value));
        await page.press(`input[type=number][data-dimension="${dimension}"]`, 'Enter');
        await page.waitForFunction(([d, v]) => window.fabatlas.u[d] === v, [dimension, value], { timeout: 30000 });
        await settle(page);
      };
      await type(1, 11);
      const before = await validHi();
      await page.fill('input[data-property="volume"][data-bound="max"]', String(tubeVolume(15, 8.5)));
      await page.press('input[data-property="volume"][data-bound="max"]', 'Enter');
      await page.waitForFunction(() => window.fabatlas.u[1] !== 11, null, { timeout: 30000 });
      await settle(page);
      const u = await page.evaluate(() => window.fabatlas.u.slice());
      const movedHi = await validHi();
      check(u[1] <= movedHi + 1e-9 && tubeVolume(u[0], u[1]) <= tubeVolume(15, 8.5) * 1.02, `the point moved into the limit (${u.map((v) => v.toFixed(2)).join(', ')})`);
      // Back to radius 15 through points within the limit (a typed point
      // outside it would snap to a sample).
      await type(1, 7);
      await type(0, 15);
      const after = await validHi();
      check(before > 11 && after <= 8.5 + 0.3 && after >= 0.5 + 3 * 2.3 - 1e-9, `a volume limit shrinks the wall's valid stretch at radius 15 (${before.toFixed(2)} -> ${after.toFixed(2)})`);
      check(page.url().includes('limits='), 'the URL carries the limit');
      const hatched = await page.locator('.slider').nth(1).locator('.segment.invalid').count();
      check(hatched >= 2, `the wall track hatches the stretch beyond the limit (${hatched} invalid segments)`);
    }
    await statusOk(page, 'at the end');
    check(errors.length === 0, 'no page errors' + (errors.length ? ': ' + errors.join('; ') : ''));

    fs.mkdirSync(out, { recursive: true });
    await page.screenshot({ path: path.join(out, 'viewer_browser.png'), fullPage: true });
    console.log('screenshot: ' + path.join(out, 'viewer_browser.png'));
});
