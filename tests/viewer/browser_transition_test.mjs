// Reconfigurables in the customiser (headless Chromium on a real run of the
// folding bench, tests/viewer/data/bench_table.yaml): "Play fold" at the
// current (valid) design plays the transition — frames advance to t = 1,
// where the design file's 90-degree turn of the top about x is what the page
// shows — with no collision; a click on an invalid cell of the validity map
// plays the invalid sample next to it and rests at its first colliding time,
// which equals `fabatlas eval`'s collision_t_begin for that sample, with
// exactly the two objects the CLI names drawn red (and red pixels on
// screen); "How to resolve it" draws the spacetime contact normal `fabatlas
// resolve` prints as an arrow on the selected object and offers the
// resolved design, which `fabatlas eval` finds valid. Keeps screenshots in
// $FABATLAS_TEST_OUTPUT/viewer_transition.png and viewer_resolve.png.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { check, clickMap, env, openPage, runBrowserTest, statusOk } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';
// A play waits for one evaluation with every check on the server (1.7 s on
// an idle host, minutes at nice 15 beside a normal-priority job): the waits
// are for events, this only bounds them.
const play = 240000;
const design = env.FABATLAS_TRANSITION_DESIGN;

// `fabatlas eval DESIGN --at ... --json` at the sample's exact values.
function cliEval(u) {
  const at = `armrest_height=${u[0]},hinge_offset=${u[1]}`;
  return JSON.parse(execFileSync(path.join(env.FABATLAS_BIN_DIR, 'fabatlas'), ['eval', design, '--at', at, '--json']).toString());
}

// Red pixels on the preview canvas (the colliding objects' colour is #d62828).
const redPixels = (page) => page.evaluate(() => {
  const src = document.querySelector('#preview canvas');
  const c = document.createElement('canvas');
  c.width = src.width; c.height = src.height;
  const ctx = c.getContext('2d');
  ctx.drawImage(src, 0, 0);
  const p = ctx.getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < p.length; i += 4) n += p[i] > 120 && p[i + 1] < 70 && p[i + 2] < 70;
  return n;
});

await runBrowserTest(env.FABATLAS_TRANSITION_RUN, async ({ server, browser }) => {
    const { page, errors } = await openPage(browser, server.url);
    const form = await page.evaluate(() => window.fabatlas.form);
    check(JSON.stringify(form.transitions) === JSON.stringify([{ from: 'bench', name: 'fold', to: 'table' }]) &&
      JSON.stringify(form.objects) === JSON.stringify(['frame', 'top']), `the form lists the state graph: ${JSON.stringify(form.transitions)}`);
    check(await page.locator('#motion-panel').isVisible(), 'the Transitions panel is shown');

    // 1. Play fold at the current design (a valid sample).
    const u = await page.evaluate(() => window.fabatlas.properties.u);
    check(cliEval(u).valid === true, `the current design (${u.join(', ')}) is valid by fabatlas eval`);
    await page.click('button[data-transition="fold"]');
    await page.waitForFunction(() => window.fabatlas.motion && window.fabatlas.motion.frame > 0, null, { timeout: play });
    const early = await page.evaluate(() => window.fabatlas.motion.t);
    await page.waitForFunction(() => window.fabatlas.motionPlays === 1, null, { timeout: play });
    const played = await page.evaluate(() => {
      const m = window.fabatlas.motion;
      return { ...m, info: document.querySelector('#motion-info').textContent };
    });
    check(played.framesShown >= 3 && played.t === 1 && early < 1 && played.frame === played.frames - 1,
      `frames advance: ${played.framesShown} frames shown, t from ${early.toFixed(3)} to ${played.t} (${played.frames} frames)`);
    check(played.firstCollision === null && played.highlighted.length === 0 && played.info.includes('no collision'),
      `no collision at the valid design: "${played.info}"`);
    // At t = 1 the top has turned 90 degrees about +x (the design file's last
    // rotation key): its pose on screen maps y to z.
    const top = await page.evaluate(() => {
      const s = window.fabatlas;
      const g = s.motionObjects().find((m) => m.name === 'top');
      return g.matrix.elements.slice();  // column-major
    });
    check(Math.abs(top[5]) < 1e-9 && Math.abs(top[6] - 1) < 1e-9 && Math.abs(top[9] + 1) < 1e-9,
      `the top turned 90 degrees about x at t = 1 (R = [[${top[0]}, ${top[4]}, ${top[8]}], [${top[1]}, ${top[5]}, ${top[9]}], [${top[2]}, ${top[6]}, ${top[10]}]])`);

    // 2. An invalid cell of the map (low armrests, hinge high above them):
    // the invalid sample next to it plays and rests at its first collision.
    await page.waitForFunction(() => window.fabatlas.map !== null, null, { timeout: 30000 });
    await clickMap(page, 610, 140);
    await page.waitForFunction(() => window.fabatlas.motionPlays === 2, null, { timeout: play });
    const bad = await page.evaluate(() => ({ ...window.fabatlas.motion, info: document.querySelector('#motion-info').textContent,
      reason: window.fabatlas.reason, colours: window.fabatlas.motionObjects().map((m) => [m.name, m.material.color.getHexString()]) }));
    const cli = cliEval(bad.u);
    const cf = cli.checks.collision_free;
    check(cli.valid === false && cli.failure === 'collision', `the sample played (${bad.u.join(', ')}) is invalid by fabatlas eval: ${cli.failure}`);
    check(bad.reason.sample >= 0 && JSON.stringify(bad.reason.sample_u) === JSON.stringify(bad.u), `it is the sample /api/reason explains (#${bad.reason.sample})`);
    check(bad.firstCollision !== null && bad.firstCollision.t === cf.measures.collision_t_begin &&
      bad.firstCollision.t_end === cf.measures.collision_t_end,
      `first colliding time ${bad.firstCollision?.t} equals fabatlas eval's collision_t_begin ${cf.measures.collision_t_begin}`);
    check(bad.t === cf.measures.collision_t_begin && bad.info.includes(`first collision at t = ${cf.measures.collision_t_begin.toFixed(4)}`),
      `the page rests there and says so: "${bad.info}"`);
    const pair = [...cf.reason.matchAll(/'(\w+)'/g)].map((m) => m[1]).slice(0, 2).sort();
    check(JSON.stringify([...bad.highlighted].sort()) === JSON.stringify(pair) &&
      bad.colours.every(([name, c]) => (c === 'd62828') === pair.includes(name)),
      `the colliding objects the CLI names (${pair.join(', ')}) are drawn red: ${JSON.stringify(bad.colours)}`);
    const red = await redPixels(page);
    check(red > 500, `red pixels on screen: ${red}`);
    fs.mkdirSync(out, { recursive: true });
    await page.screenshot({ path: path.join(out, 'viewer_transition.png'), fullPage: true });
    console.log('screenshot: ' + path.join(out, 'viewer_transition.png'));

    // 3. Scrubbing the time slider before the collision: nothing red.
    await page.evaluate((t) => {
      const input = document.querySelector('#motion-t');
      input.value = String(t);
      input.dispatchEvent(new Event('input'));
    }, bad.firstCollision.t / 2);
    await page.waitForFunction((t) => window.fabatlas.motion.t < t, bad.firstCollision.t, { timeout: 10000 });
    check((await page.evaluate(() => window.fabatlas.motion.highlighted.length)) === 0, 'before the first colliding time nothing is red');

    // 4. Playing the same sample again reuses the page's answer: no request.
    let asked = 0;
    page.on('request', (r) => { if (r.url().includes('/api/state_graph')) asked += 1; });
    await page.click('#motion-why');
    await page.waitForFunction(() => window.fabatlas.motionPlays === 3, null, { timeout: play });
    const again = await page.evaluate(() => window.fabatlas.motion);
    check(asked === 0 && again.t === bad.firstCollision.t && JSON.stringify(again.u) === JSON.stringify(bad.u),
      `"Play invalid sample" replays it from the page's copy (${asked} requests), resting at t = ${again.t}`);

    // 5. How to resolve it (Reconfigurables Sec. 6): an arrow on the selected
    // object along the spacetime contact normal `fabatlas resolve` prints,
    // and the resolved design, valid by `fabatlas eval` with every check;
    // "Use the resolved design" moves the customiser there.
    check(await page.locator('#resolve-hint').isVisible(), 'a played collision offers "How to resolve it"');
    await page.click('#resolve-hint');
    await page.waitForFunction(() => window.fabatlas.resolvePlays === 1, null, { timeout: play });
    const res = await page.evaluate(() => ({ r: window.fabatlas.resolution, arrows: window.fabatlas.hintArrows,
      drawn: window.fabatlas.motionObjects()[0].parent.children.filter((c) => c.name.startsWith('hint:')).map((c) => c.name),
      info: document.querySelector('#resolve-info').textContent }));
    const at = `armrest_height=${bad.u[0]},hinge_offset=${bad.u[1]}`;
    const printed = execFileSync(path.join(env.FABATLAS_BIN_DIR, 'fabatlas'), ['resolve', design, '--at', at]).toString();
    const normal = printed.match(/spacetime normal of '(\w+)': \[([-\d.]+), ([-\d.]+), ([-\d.]+)\]/);
    check(normal !== null && res.arrows.length === 1 && res.arrows[0].object === normal[1] &&
      res.arrows[0].normal.every((x, k) => Math.abs(x - Number(normal[k + 2])) <= 0.0005) &&
      JSON.stringify(res.drawn) === JSON.stringify([`hint:${normal[1]}`]),
      `the arrow on '${res.arrows[0]?.object}' points along (${res.arrows[0]?.normal.map((x) => x.toFixed(3))}), as fabatlas resolve prints: ${normal?.[0]}`);
    check(res.r.resolution?.resolved === true && cliEval(res.r.resolution.u).valid === true,
      `the resolved design (${res.r.resolution?.u.join(', ')}) is valid by fabatlas eval`);
    check(res.info.includes('resolved: ') && res.info.includes(`move '${normal?.[1]}' along`), `the page says so: "${res.info}"`);
    const yellow = await page.evaluate(() => {
      const src = document.querySelector('#preview canvas');
      const c = document.createElement('canvas');
      c.width = src.width; c.height = src.height;
      const ctx = c.getContext('2d');
      ctx.drawImage(src, 0, 0);
      const p = ctx.getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < p.length; i += 4) n += p[i] > 200 && p[i + 1] > 150 && p[i + 1] < 230 && p[i + 2] < 80;
      return n;
    });
    check(yellow > 50, `the arrow is on screen: ${yellow} yellow pixels`);
    await page.screenshot({ path: path.join(out, 'viewer_resolve.png'), fullPage: true });
    await page.click('#resolve-apply');
    await page.waitForFunction((u) => JSON.stringify(window.fabatlas.u) === JSON.stringify(u), res.r.resolution.u, { timeout: 30000 });
    check(await page.evaluate(() => window.fabatlas.motion === null && window.fabatlas.resolution === null),
      '"Use the resolved design" leaves the transition for the resolved design');
    await statusOk(page, 'at the resolved design');

    // 6. Back to the preview (after playing the invalid sample once more).
    await page.click('#motion-why');
    await page.waitForFunction(() => window.fabatlas.motionPlays === 4, null, { timeout: play });
    await page.click('#motion-back');
    check(await page.evaluate(() => window.fabatlas.motion === null), 'back to the preview');
    await statusOk(page, 'at the end');
    check(errors.length === 0, 'no page errors' + (errors.length ? ': ' + errors.join('; ') : ''));
});
