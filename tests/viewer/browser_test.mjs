// The web customiser in headless Chromium (playwright-core, Debian's
// chromium): load the page that `fabatlas serve` serves for a real run's
// artifact, drag a slider and see the preview change, drag a slider into an
// invalid stretch and see it come to rest in a valid interval, hover an
// invalid stretch and see its failure type. Keeps a screenshot in
// $FABATLAS_TEST_OUTPUT/viewer_browser.png. Exit status 0 = pass.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { chromium } from 'playwright-core';

const env = process.env;
const bin = env.FABATLAS_BIN_DIR;
const run = env.FABATLAS_VIEWER_RUN;
const out = env.FABATLAS_TEST_OUTPUT ?? '.';
const failures = [];
const check = (ok, what) => { console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`); if (!ok) failures.push(what); };

function startServer() {
  const child = spawn(path.join(bin, 'fabatlas'), ['serve', run, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
  return new Promise((resolve, reject) => {
    let text = '';
    const timer = setTimeout(() => reject(new Error('fabatlas serve did not start: ' + text)), 30000);
    const onData = (d) => {
      text += d;
      const m = text.match(/at (http:\/\/127\.0\.0\.1:\d+\/)/);
      if (m) { clearTimeout(timer); resolve({ child, url: m[1] }); }
    };
    child.stdout.on('data', onData);
    child.stderr.on('data', onData);
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`fabatlas serve exited ${code}: ${text}`)); });
  });
}

// Screen x of value v on slider d's track (the thumb is 16 px wide).
async function xOf(page, d, v) {
  const box = await page.locator(`input[data-dimension="${d}"]`).boundingBox();
  const dim = await page.evaluate((d) => window.fabatlas.form.dimensions[d], d);
  const t = (v - dim.lo) / (dim.hi - dim.lo);
  return { x: box.x + 8 + t * (box.width - 16), y: box.y + box.height / 2 };
}

async function drag(page, d, to) {
  const u = await page.evaluate(() => window.fabatlas.u);
  const from = await xOf(page, d, u[d]);
  const target = await xOf(page, d, to);
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  for (let i = 1; i <= 12; ++i) await page.mouse.move(from.x + ((target.x - from.x) * i) / 12, from.y);
  await page.mouse.up();
}

async function settle(page) {
  // Quiet: no update in flight and the preview matches the properties' sample.
  await page.waitForFunction(() => {
    const s = window.fabatlas;
    return s.properties && s.previewSample === s.properties.sample;
  }, null, { timeout: 60000 });
  await page.waitForTimeout(300);
  await page.waitForFunction(() => window.fabatlas.previewSample === window.fabatlas.properties.sample, null, { timeout: 60000 });
}

const canvasPixels = (page) => page.evaluate(() => document.querySelector('#preview canvas').toDataURL());

let server, browser;
try {
  server = await startServer();
  browser = await chromium.launch({
    executablePath: env.FABATLAS_CHROMIUM ?? '/usr/bin/chromium',
    args: ['--no-sandbox', '--no-proxy-server', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
  const page = await browser.newPage({ viewport: { width: 1200, height: 760 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(server.url);
  await page.waitForFunction(() => window.fabatlas.ready && window.fabatlas.previewCount >= 1, null, { timeout: 60000 });
  await settle(page);
  check(await page.evaluate(() => window.fabatlas.form.dimensions.length) === 2, 'two sliders for radius and wall');

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
      input: parseFloat(document.querySelector('input[data-dimension="1"]').value),
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

  // 4. Starting-point thumbnails and the validity map are drawn.
  await page.waitForFunction(() => [...document.querySelectorAll('#starts img')].some((i) => i.src.startsWith('data:image/png')), null, { timeout: 60000 });
  check(await page.locator('#starts button').count() >= 1, 'starting-point thumbnails');
  check(errors.length === 0, 'no page errors' + (errors.length ? ': ' + errors.join('; ') : ''));

  fs.mkdirSync(out, { recursive: true });
  await page.screenshot({ path: path.join(out, 'viewer_browser.png'), fullPage: true });
  console.log('screenshot: ' + path.join(out, 'viewer_browser.png'));
} catch (e) {
  failures.push(String(e.stack ?? e));
  console.log('FAIL ' + (e.stack ?? e));
} finally {
  if (browser) await browser.close();
  if (server) server.child.kill('SIGTERM');
}
process.exit(failures.length ? 1 : 0);
