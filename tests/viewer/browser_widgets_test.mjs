// Integer and enumerated parameters in the customiser (headless Chromium on
// the peg rail run, tests/viewer/data/peg_rail_design.yaml: `pegs` pegs
// (integer 1..5), thin or thick (enum: radius 1 or 2 mm), fitting along a
// rail of `length` mm when pegs (2 r + 1) <= length). At length 15 the
// closed form allows 5 thin or 3 thick pegs. Dragging the integer slider
// only ever sets whole numbers; the enum dropdown and the enum slider send
// the value's index to the API (seen in the requests); the valid stretches,
// the disabled dropdown entries, the URL and the preview's sample and volume
// (the 15 x 6 x 2 mm rail plus the pegs' 5.5 mm above it) follow the closed
// form. Keeps a screenshot in $FABATLAS_TEST_OUTPUT/viewer_widgets.png.
import fs from 'node:fs';
import path from 'node:path';
import { check, drag, env, openPage, runBrowserTest, settle, statusOk } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';
const pitch = (peg) => 2 * (1 + peg) + 1;
const fits = (length, pegs, peg) => pegs * pitch(peg) <= length;
// Material volume at a length away from the rail's bulge: rail + pegs above it.
const volume = (length, pegs, peg) => length * 6 * 2 + pegs * Math.PI * (1 + peg) ** 2 * 5.5;

await runBrowserTest(env.FABATLAS_VIEWER_PEG_RUN, async ({ server, browser }) => {
    const { page, errors } = await openPage(browser, server.url + '?length=15&pegs=2&peg=thin');
    const requests = [];
    page.on('request', (r) => { if (r.url().includes('/api/')) requests.push(decodeURIComponent(r.url())); });
    const dims = await page.evaluate(() => window.fabatlas.form.dimensions.map((d) => [d.name, d.kind]));
    check(JSON.stringify(dims) === JSON.stringify([['length', 'real'], ['pegs', 'integer'], ['peg', 'enumerated']]), `parameters: ${JSON.stringify(dims)}`);
    check(await page.evaluate(() => JSON.stringify(window.fabatlas.u)) === '[15,2,0]', 'the URL sets length 15, 2 thin pegs');
    check(await page.locator('input[type=range][data-dimension="1"]').getAttribute('step') === '1' &&
      await page.locator('input[type=number][data-dimension="1"]').getAttribute('step') === '1', 'the integer slider and box step by 1');
    const labels = await page.locator('select[data-dimension="2"] option').allTextContents();
    check(JSON.stringify(labels) === '["thin","thick"]', `the enum is a dropdown of its values: ${JSON.stringify(labels)}`);

    // 1. Drag the integer slider from 2 towards 4.4: whole numbers all the way, ends at 4.
    const seen = [];
    await drag(page, 1, 4.4, async () => seen.push(await page.evaluate(() => [window.fabatlas.u[1],
      document.querySelector('input[type=range][data-dimension="1"]').value])));
    await settle(page);
    check(seen.every(([u, v]) => Number.isInteger(u) && String(u) === v), `every value on the way is whole: ${JSON.stringify(seen.map(([u]) => u))}`);
    const at4 = await page.evaluate(() => ({ u: window.fabatlas.u.slice(), p: window.fabatlas.properties, sample: window.fabatlas.previewSample }));
    check(at4.u[1] === 4 && at4.p.u[1] === 4 && at4.sample === at4.p.sample, `the slider rests at 4 and the preview is sample #${at4.sample} at ${JSON.stringify(at4.p.u)}`);
    check(Math.abs(at4.p.properties.volume - volume(15, 4, 0)) < 0.02 * volume(15, 4, 0),
      `its volume ${at4.p.properties.volume.toFixed(1)} mm³ is the rail and 4 thin pegs' ${volume(15, 4, 0).toFixed(1)}`);
    check(/[?&]pegs=4(&|$)/.test(page.url()), `the URL says pegs=4: ${page.url()}`);
    // All 5 thin pegs fit at length 15: the whole integer track is valid.
    const thinStretches = await page.evaluate(() => window.fabatlas.stretches[1]);
    check(thinStretches.every((s) => s.valid) && fits(15, 5, 0), `thin pegs: the integer track is valid from 1 to 5 (${JSON.stringify(thinStretches)})`);
    // Thick pegs at 4 would not fit (4 x 5 > 15): the dropdown disables it.
    check(await page.locator('select[data-dimension="2"] option[value="1"]').isDisabled() && !fits(15, 4, 1), 'at 4 pegs, thick is offered but disabled');

    // 2. Back to 3 pegs with the number box (3.4 rounds to 3), then thick
    // from the dropdown: the API is asked with the value's index, 1.
    await page.fill('input[type=number][data-dimension="1"]', '3.4');
    await page.press('input[type=number][data-dimension="1"]', 'Enter');
    await page.waitForFunction(() => window.fabatlas.u[1] === 3, null, { timeout: 30000 });
    await settle(page);
    check(!(await page.locator('select[data-dimension="2"] option[value="1"]').isDisabled()) && fits(15, 3, 1), 'at 3 pegs, thick is enabled');
    requests.length = 0;
    await page.selectOption('select[data-dimension="2"]', 'thick');
    await page.waitForFunction(() => window.fabatlas.u[2] === 1, null, { timeout: 30000 });
    await settle(page);
    check(requests.some((r) => r.includes('/api/intervals?u=15,3,1')) && requests.some((r) => r.includes('/api/properties?u=15,3,1')),
      `the enum's index reaches the API: ${requests.filter((r) => r.includes('intervals')).join(' ')}`);
    const thick = await page.evaluate(() => ({ s: window.fabatlas.stretches[1], p: window.fabatlas.properties }));
    const validHi = Math.max(...thick.s.filter((s) => s.valid).map((s) => s.hi));
    check(validHi === Math.floor(15 / pitch(1)) && thick.s.some((s) => !s.valid && s.lo === 3 && s.hi === 5),
      `thick pegs: the integer track is valid up to ${validHi} = floor(15 / 5), invalid beyond (${JSON.stringify(thick.s)})`);
    check(JSON.stringify(thick.p.u) === '[15,3,1]' && Math.abs(thick.p.properties.volume - volume(15, 3, 1)) < 0.02 * volume(15, 3, 1),
      `the preview is 3 thick pegs: ${thick.p.properties.volume.toFixed(1)} vs ${volume(15, 3, 1).toFixed(1)} mm³`);
    check(/[?&]peg=thick(&|$)/.test(page.url()) && /[?&]pegs=3(&|$)/.test(page.url()), `the URL names the value: ${page.url()}`);

    // 3. Drag the integer slider deep into the invalid stretch: it rests at 3.
    await drag(page, 1, 4.9);
    await settle(page);
    const rest = await page.evaluate(() => [window.fabatlas.u[1], document.querySelector('input[type=range][data-dimension="1"]').value]);
    check(rest[0] === 3 && rest[1] === '3', `dragged towards 5 thick pegs, the slider rests at ${rest[0]}`);

    // 4. The enum's own slider: back to thin (index 0) reaches the API too.
    requests.length = 0;
    await drag(page, 2, 0);
    await page.waitForFunction(() => window.fabatlas.u[2] === 0, null, { timeout: 30000 });
    await settle(page);
    check(requests.some((r) => r.includes('/api/properties?u=15,3,0')) && await page.locator('select[data-dimension="2"]').inputValue() === '0',
      'the enum slider sets thin: the API is asked for index 0 and the dropdown follows');

    // 5. The URL opens the same design, enum by label.
    await page.selectOption('select[data-dimension="2"]', 'thick');
    await page.waitForFunction(() => window.fabatlas.u[2] === 1, null, { timeout: 30000 });
    await settle(page);
    const again = await openPage(browser, page.url());
    const a = await page.evaluate(() => ({ u: window.fabatlas.u, s: window.fabatlas.previewSample }));
    const b = await again.page.evaluate(() => ({ u: window.fabatlas.u, s: window.fabatlas.previewSample }));
    check(JSON.stringify(a) === JSON.stringify(b) && await again.page.locator('select[data-dimension="2"]').inputValue() === '1',
      `the URL opens the same design (${JSON.stringify(b)})`);
    await again.page.close();

    await statusOk(page, 'at the end');
    check(errors.length === 0, 'no page errors' + (errors.length ? ': ' + errors.join('; ') : ''));
    fs.mkdirSync(out, { recursive: true });
    await page.mouse.move(1, 1);  // no tooltip in the picture
    await page.waitForFunction(() => document.querySelector('#tooltip').hidden, null, { timeout: 10000 });
    await page.screenshot({ path: path.join(out, 'viewer_widgets.png'), fullPage: true });
    console.log('screenshot: ' + path.join(out, 'viewer_widgets.png'));
});
