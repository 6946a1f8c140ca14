// Parts and colours in the customiser (issue 32; headless Chromium on the
// name plate run, tests/viewer/data/name_plate.scad: a steelblue plate, an
// orange stand and a crimson knob, three top-level bodies; its import
// data/name_plate.yaml sampled by data/name_plate.job.yaml).
//   1. /api/preview.glb carries one node per body, each with a material
//      named after its part whose baseColorFactor is its color() (the CSS
//      keyword's sRGB, made linear as glTF wants).
//   2. The preview on the page shows the three colours: pixels of the
//      canvas whose hue is the plate's blue, the stand's orange and the knob's
//      red (the default material is a tan none of them is).
//   3. The 3MF download holds three objects with basematerials of the three
//      colours (#4682B4, #FFA500, #DC143C: CSS Color Module Level 3), and
//      part=NAME gives one body's STL.
// Keeps a screenshot in $FABATLAS_TEST_OUTPUT/viewer_parts.png
// (docs/images/customiser-parts.png).
import path from 'node:path';
import zlib from 'node:zlib';
import { check, env, openPage, runBrowserTest, statusOk } from './browser_support.mjs';

const out = env.FABATLAS_TEST_OUTPUT ?? '.';
// CSS Color Module Level 3, 4.3 (extended colour keywords).
const css = { steelblue: [70, 130, 180], orange: [255, 165, 0], crimson: [220, 20, 60] };
const linear = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);

// The JSON chunk of a GLB (glTF 2.0, Sec. 4.4.3).
function glbJson(buffer) {
  const length = buffer.readUInt32LE(12);
  return JSON.parse(buffer.subarray(20, 20 + length).toString('utf8'));
}

// The 3D/3dmodel.model entry of a 3MF (a ZIP of deflated entries).
function threeMfModel(buffer) {
  for (let at = 0; at + 30 < buffer.length;) {
    if (buffer.readUInt32LE(at) !== 0x04034b50) break;
    const size = buffer.readUInt32LE(at + 18), nameLength = buffer.readUInt16LE(at + 26), extra = buffer.readUInt16LE(at + 28);
    const name = buffer.subarray(at + 30, at + 30 + nameLength).toString();
    const data = buffer.subarray(at + 30 + nameLength + extra, at + 30 + nameLength + extra + size);
    if (name === '3D/3dmodel.model') return zlib.inflateRawSync(data).toString();
    at += 30 + nameLength + extra + size;
  }
  return '';
}

await runBrowserTest(env.FABATLAS_VIEWER_PLATE_RUN, async ({ server, browser }) => {
  const { page, errors } = await openPage(browser, server.url + '?width=70&height=20');

  // 1. The preview's glTF.
  const u = await page.evaluate(() => window.fabatlas.u.join(','));
  const glb = glbJson(Buffer.from(await (await page.request.get(server.url + 'api/preview.glb?u=' + u)).body()));
  const parts = (glb.nodes ?? []).filter((n) => n.mesh !== undefined);
  check(parts.length === 3, `three part nodes: ${JSON.stringify(parts.map((n) => n.name))}`);
  const expected = { body1: 'steelblue', body2: 'orange', body3: 'crimson' };
  for (const node of parts) {
    const material = glb.materials?.[glb.meshes[node.mesh].primitives[0].material];
    const want = css[expected[node.name]];
    const got = material?.pbrMetallicRoughness?.baseColorFactor ?? [];
    check(want && material.name === 'part ' + node.name && want.every((c, k) => Math.abs(got[k] - linear(c / 255)) < 1e-6),
      `${node.name}: material ${material?.name} colour ${JSON.stringify(got)} is ${expected[node.name]}`);
  }

  // 2. The canvas shows the three colours.
  const hues = await page.evaluate(async () => {
    const canvas = document.querySelector('#preview canvas');
    const img = new Image();
    img.src = canvas.toDataURL();
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width; c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const count = { blue: 0, orange: 0, red: 0 };
    for (let i = 0; i < d.length; i += 4) {
      const [r, gg, b] = [d[i], d[i + 1], d[i + 2]];
      const max = Math.max(r, gg, b), min = Math.min(r, gg, b);
      if (max - min < 40) continue;  // greys: background, grid
      let h = max === r ? ((gg - b) / (max - min)) * 60 : max === gg ? (2 + (b - r) / (max - min)) * 60 : (4 + (r - gg) / (max - min)) * 60;
      if (h < 0) h += 360;
      if (h > 195 && h < 225 && b > r) count.blue++;       // steelblue: 207 degrees
      else if (h > 32 && h < 45 && r > 150) count.orange++; // orange: 39 degrees (the default tan is 30 and pale)
      else if (h > 335 || h < 5) count.red++;              // crimson: 348 degrees
    }
    return count;
  });
  check(hues.blue > 500 && hues.orange > 500 && hues.red > 100, `the preview shows blue, orange and red pixels: ${JSON.stringify(hues)}`);

  // 3. Downloads: a 3MF of three coloured objects, one body's STL.
  const three = await page.request.get(server.url + 'api/export?format=3mf&u=' + u);
  const model = threeMfModel(Buffer.from(await three.body()));
  const colours = [...model.matchAll(/displaycolor="(#[0-9A-F]+)"/g)].map((m) => m[1]);
  const objects = [...model.matchAll(/<object id="\d+" type="model" name="([^"]+)" pid="1" pindex="(\d+)"/g)]
    .map((m) => [m[1], colours[Number(m[2])]]);
  check(JSON.stringify(objects) === JSON.stringify([['body1', '#4682B4FF'], ['body2', '#FFA500FF'], ['body3', '#DC143CFF']]),
    `the 3MF's objects and colours: ${JSON.stringify(objects)}`);
  check(three.headers()['x-parts'] === 'body1 #4682b4,body2 #ffa500,body3 #dc143c', `X-Parts: ${three.headers()['x-parts']}`);
  const knob = await page.request.get(server.url + 'api/export?format=stl&part=body3&u=' + u);
  const triangles = Buffer.from(await knob.body()).readUInt32LE(80);
  check(knob.status() === 200 && triangles > 0 && triangles < 400, `part=body3 is the knob alone: ${triangles} triangles`);

  await statusOk(page, 'parts');
  check(errors.length === 0, `no page errors or failed API answers: ${JSON.stringify(errors)}`);
  await page.screenshot({ path: path.join(out, 'viewer_parts.png'), fullPage: true });
  console.log('screenshot: ' + path.join(out, 'viewer_parts.png'));
});
