// What the customiser's browser tests share: a real `fabatlas serve` on a
// free port, headless Chromium (Debian's, through playwright-core), the
// ok/FAIL log, one test's run from start to exit status (runBrowserTest),
// waiting for the page to be quiet, the status line.
import { spawn } from 'node:child_process';
import path from 'node:path';
import { chromium } from 'playwright-core';

export const env = process.env;
export const failures = [];
export const check = (ok, what) => { console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`); if (!ok) failures.push(what); };

// `fabatlas serve RUN --port 0 ARGS...`; resolves with {child, url} once it prints its URL.
export function startServer(run, args = []) {
  const child = spawn(path.join(env.FABATLAS_BIN_DIR, 'fabatlas'), ['serve', run, '--port', '0', ...args], { stdio: ['ignore', 'pipe', 'pipe'] });
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

// Runs one browser test: `fabatlas serve RUN ARGS...` and Chromium, then
// `body({ server, browser })`; a throw is a failure. Closes both and exits the
// process with status 1 if any check failed, else 0.
export async function runBrowserTest(run, body, args = []) {
  let server, browser;
  try {
    server = await startServer(run, args);
    browser = await launchBrowser();
    await body({ server, browser });
  } catch (e) {
    failures.push(String(e.stack ?? e));
    console.log('FAIL ' + (e.stack ?? e));
  } finally {
    if (browser) await browser.close();
    if (server) server.child.kill('SIGTERM');
  }
  process.exit(failures.length ? 1 : 0);
}

export function launchBrowser() {
  return chromium.launch({
    executablePath: env.FABATLAS_CHROMIUM ?? '/usr/bin/chromium',
    args: ['--no-sandbox', '--no-proxy-server', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

// Opens the page and waits for its first preview. `errors` collects what
// fails a test whatever it checks: page errors, any 4xx/5xx answer of the API
// (/api/*), console errors reporting a Content-Security-Policy violation, and
// dialogs (alert, confirm, prompt: the page opens none).
export async function openPage(browser, url, viewport = { width: 1200, height: 900 }) {
  const page = await browser.newPage({ viewport, acceptDownloads: true });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('response', (r) => {
    const u = new URL(r.url());
    if (u.pathname.startsWith('/api/') && r.status() >= 400) errors.push(`${r.status()} from ${u.pathname}${decodeURIComponent(u.search)}`);
  });
  page.on('console', (m) => {
    if (m.type() === 'error' && /Content.Security.Policy|Refused to/i.test(m.text())) errors.push('CSP violation: ' + m.text());
  });
  page.on('dialog', (d) => { errors.push(`dialog (${d.type()}): ${d.message()}`); d.dismiss().catch(() => {}); });
  await page.goto(url, { timeout: 120000 });
  await page.waitForFunction(() => window.fabatlas.ready && window.fabatlas.previewCount >= 1, null, { timeout: 60000 });
  await settle(page);
  return { page, errors };
}

export async function settle(page) {
  // Quiet: no update in flight and the preview matches the properties' sample.
  await page.waitForFunction(() => {
    const s = window.fabatlas;
    return s.properties && s.previewSample === s.properties.sample;
  }, null, { timeout: 60000 });
  await page.waitForTimeout(300);
  await page.waitForFunction(() => window.fabatlas.previewSample === window.fabatlas.properties.sample, null, { timeout: 60000 });
}

// The status line: not an error.
export async function statusOk(page, what) {
  const st = await page.evaluate(() => ({ text: document.querySelector('#status').textContent,
    error: document.querySelector('#status').classList.contains('error') || window.fabatlas.error !== null }));
  check(!st.error, `${what}: status line "${st.text}" shows no error`);
}

// A click on the validity map at parameter values (a, b) of its axes.
export async function clickMap(page, a, b) {
  const box = await page.locator('#map').boundingBox();
  const m = await page.evaluate(() => window.fabatlas.map);
  await page.locator('#map').click({ position: {
    x: ((a - m.a_range[0]) / (m.a_range[1] - m.a_range[0])) * box.width,
    y: box.height - ((b - m.b_range[0]) / (m.b_range[1] - m.b_range[0])) * box.height } });
}

// Screen x of value v on slider d's track (the thumb is 16 px wide).
export async function xOf(page, d, v) {
  const box = await page.locator(`input[type=range][data-dimension="${d}"]`).boundingBox();
  const dim = await page.evaluate((d) => window.fabatlas.form.dimensions[d], d);
  const t = (v - dim.lo) / (dim.hi - dim.lo);
  return { x: box.x + 8 + t * (box.width - 16), y: box.y + box.height / 2 };
}

// Drags slider d's thumb to value `to` in 12 mouse moves; onStep (optional)
// runs after each move.
export async function drag(page, d, to, onStep = null) {
  const u = await page.evaluate(() => window.fabatlas.u);
  const from = await xOf(page, d, u[d]);
  const target = await xOf(page, d, to);
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  for (let i = 1; i <= 12; ++i) {
    await page.mouse.move(from.x + ((target.x - from.x) * i) / 12, from.y);
    if (onStep) await onStep(i);
  }
  await page.mouse.up();
}
