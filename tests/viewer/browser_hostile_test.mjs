// Hostile input in the web customiser (issue 31): a real `fabatlas serve` of
// an artifact whose every free-text field is markup meant to run script:
// the design's name, descriptions, groups and enum values
// (data/hostile_design.yaml), the job's material names (data/hostile.yaml),
// failure types and a property name (written into the artifact by
// hostile_artifact.cc, as a hand-made artifact could), and presets the user
// saves or imports. Checks that each shows exactly as written, as text (no
// element of the markup exists), that no script ran (document.title stays
// the page's, no dialog, no Content-Security-Policy violation, no page
// error, no 4xx/5xx from /api/*), and that the page's CSP blocks an inline
// script (a check that fails if the policy is dropped). Exit status 0 = pass.
import { check, env, openPage, runBrowserTest, settle, statusOk, xOf } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';
// As in data/hostile_design.yaml, data/hostile.yaml and hostile_artifact.cc.
const H = {
  name: `<img src=x onerror="document.title='XSS'">`,
  radius: { description: `<img src=x onerror="document.title='XSS-description'">`, group: `"><script>document.title='XSS-group'</script>` },
  wall: { description: `</div><svg onload="document.title='XSS-svg'">`, group: `<b onmouseover="document.title='XSS-b'">Strength</b>` },
  finish: { description: `<a href="javascript:document.title='XSS-a'">finish</a>`,
    values: [`<img src=x onerror="document.title='XSS-enum'">`, `"><iframe srcdoc='<script>parent.document.title=1</script>'>`] },
  materials: [`<img src=x onerror="document.title='XSS-material'">`, `"><script>document.title='XSS-material2'</script>`],
  failure: `<img src=x onerror="document.title='XSS-failure'">`,
  property: `<svg onload="document.title='XSS-property'">`,
  preset: `<img src=x onerror="document.title='XSS-preset'">`,
  imported: `"><script>document.title='XSS-imported'</script>`,
  file: `"><img src=x onerror=alert(1)>.json`,
};
const title = `${H.name} — fabatlas customiser`;
// Elements the markup above would create if it were parsed as HTML.
const injected = (page) => page.evaluate(() => document.querySelectorAll(
  'img[src="x"], iframe, svg, b, a, script:not([src]), legend *, #readout td *, #readout th *, .description *, .name *, option *').length);

await runBrowserTest(env.FABATLAS_HOSTILE_ART, async ({ server, browser }) => {
  const { page, errors } = await openPage(browser, server.url);
  const csp = (await page.request.get(server.url)).headers()['content-security-policy'] ?? '';
  check(csp.includes("script-src 'self'") && !csp.includes('unsafe-inline'), `the page's CSP forbids inline script: ${csp}`);

  // Design fields: name, per parameter its group, name label's tooltip,
  // description, and the enum's values, exactly as written.
  const shown = await page.evaluate(() => ({
    title: document.title,
    h1: document.querySelector('#title').textContent,
    dims: [0, 1, 2].map((d) => {
      const box = document.querySelector(`input[type=range][data-dimension="${d}"]`).closest('.slider');
      return { group: box.closest('fieldset')?.querySelector('legend').textContent ?? null,
        tooltip: box.querySelector('.name').title, description: box.querySelector('.description').textContent };
    }),
    values: [...document.querySelectorAll('select[data-dimension="2"] option')].map((o) => o.textContent),
    materials: [...document.querySelectorAll('#readout tr.material td:first-child')].map((t) => t.textContent),
    properties: [...document.querySelectorAll('#readout th')].map((t) => t.textContent),
    limits: [...document.querySelectorAll('#limits .limit .name')].map((n) => n.textContent),
    legend: document.querySelector('#map-legend').textContent,
  }));
  check(shown.title === title && shown.h1 === title, `the design's name as text in the title: ${JSON.stringify(shown.title)}`);
  const dimsWant = [
    { group: H.radius.group, tooltip: H.radius.description, description: H.radius.description },
    { group: H.wall.group, tooltip: H.wall.description, description: H.wall.description },
    { group: null, tooltip: H.finish.description, description: H.finish.description }];
  check(JSON.stringify(shown.dims) === JSON.stringify(dimsWant), `groups and descriptions as text: ${JSON.stringify(shown.dims)}`);
  check(JSON.stringify(shown.values) === JSON.stringify(H.finish.values), `enum values as text: ${JSON.stringify(shown.values)}`);
  check(JSON.stringify(shown.materials) === JSON.stringify(H.materials), `material names as text: ${JSON.stringify(shown.materials)}`);
  check(shown.properties.includes(H.property), `the property name as text: ${JSON.stringify(shown.properties)}`);
  check(shown.limits.includes(H.property) && H.materials.every((m) => shown.limits.includes(`weight in ${m} (g)`) && shown.limits.includes(`cost in ${m}`)),
    `limits name the property and the materials as text: ${JSON.stringify(shown.limits)}`);
  check(shown.legend.includes(H.failure), `the map legend names the failure type as text: ${JSON.stringify(shown.legend)}`);

  // Hover an invalid stretch of the wall slider: the tooltip names the failure type.
  const invalid = await page.evaluate(() => window.fabatlas.stretches[1].find((s) => !s.valid));
  if (!invalid) check(false, 'the wall slider has an invalid stretch');
  else {
    const p = await xOf(page, 1, (invalid.lo + invalid.hi) / 2);
    await page.mouse.move(p.x, p.y - 3);
    await page.mouse.move(p.x, p.y);
    await page.waitForFunction(() => window.fabatlas.reasonCount >= 1, null, { timeout: 30000 });
    const tip = await page.evaluate(() => ({ text: document.querySelector('#tooltip').textContent,
      failures: document.querySelector('#tooltip').dataset.failures, title: document.querySelector('.segment.invalid').title }));
    check(tip.failures === H.failure && tip.title.includes(H.failure), `the tooltip names the failure type as text: ${JSON.stringify(tip)}`);
  }

  // Starting points: their tooltips name the enum's value as text.
  await page.waitForFunction(() => document.querySelectorAll('#starts button').length > 0, null, { timeout: 60000 });
  const starts = await page.evaluate(() => [...document.querySelectorAll('#starts button')].map((b) => b.title));
  check(starts.some((t) => H.finish.values.some((v) => t.includes(`finish ${v}`))), `starting points' tooltips as text: ${JSON.stringify(starts[0])}`);

  // Presets: one saved under a hostile name, one imported from a file with a
  // hostile set name, file name and enum value; the imported one applies.
  await page.fill('#preset-name', H.preset);
  await page.click('#preset-save');
  await page.setInputFiles('#preset-import', { name: H.file, mimeType: 'application/json',
    buffer: Buffer.from(JSON.stringify({ parameterSets: { [H.imported]: { radius: '12', wall: '4', finish: H.finish.values[1] } }, fileFormatVersion: '1' })) });
  await page.waitForFunction(() => document.querySelector('#status').textContent.startsWith('loaded 1 presets'), null, { timeout: 30000 });
  const presetStatus = await page.locator('#status').textContent();
  check(presetStatus === `loaded 1 presets from ${H.file}`, `the import's status line names the file as text: ${JSON.stringify(presetStatus)}`);
  const presets = await page.evaluate(() => [...document.querySelectorAll('#preset option')].map((o) => [o.value, o.textContent]));
  check(presets.some(([v, t]) => v === H.preset && t === H.preset) && presets.some(([v, t]) => v === H.imported && t === H.imported),
    `saved and imported preset names as text: ${JSON.stringify(presets)}`);
  await page.selectOption('#preset', H.imported);
  await page.waitForFunction(() => window.fabatlas.properties && JSON.stringify(window.fabatlas.properties.u.slice(2)) === '[1]', null, { timeout: 60000 });
  await settle(page);
  const applied = await page.evaluate(() => ({ u: window.fabatlas.u, selected: document.querySelector('select[data-dimension="2"]').selectedOptions[0].textContent,
    url: decodeURIComponent(location.search) }));
  check(JSON.stringify(applied.u) === '[12,4,1]' && applied.selected === H.finish.values[1],
    `the imported preset applies, its enum value by label: ${JSON.stringify(applied)}`);
  await statusOk(page, 'after the preset');

  // Nothing ran and nothing of the markup became elements.
  await page.waitForTimeout(1000);
  await page.screenshot({ path: `${out}/viewer_hostile.png` });
  check(await page.evaluate(() => document.title) === title, 'document.title is still the page\'s (no script ran)');
  check(await injected(page) === 0, 'no element of the hostile markup exists');
  check(errors.length === 0, 'no page errors, dialogs, CSP violations or API errors' + (errors.length ? ': ' + errors.join('; ') : ''));

  // The policy itself: an inline script added to the page does not run, and
  // Chromium reports the violation (would fail without the CSP header).
  const before = errors.length;
  const ran = await page.evaluate(async () => {
    const s = document.createElement('script');
    s.textContent = 'window.inlineRan = true';
    document.body.append(s);
    await new Promise((r) => setTimeout(r, 200));
    return window.inlineRan === true;
  });
  await page.waitForTimeout(300);
  check(!ran && errors.slice(before).some((e) => e.startsWith('CSP violation')), `an inline script is blocked by the CSP (${errors.slice(before).join('; ')})`);
});
