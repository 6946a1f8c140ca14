#!/usr/bin/env node
// Manifold (npm manifold-3d, WASM, one thread) evaluating an OpenSCAD CSG
// tree: the peer for fabatlas's exact mesh road (docs/openscad.md, "Manifold
// as a peer"; docs/benchmarks.md).
//
//   node --single-threaded bench/scad/manifold_csg.mjs MODEL.csg|MODEL.scad [--repeats 5]
//        [--stl OUT.stl] [--json] [-D name=value ...]
//
// (--single-threaded: V8 without worker threads, so WASM compilation and GC
// run on the one thread too; Manifold's WASM build has no threads of its own.
// Without it, node 20 hung now and then in a corpus run, every thread in a
// futex wait.)
//
// A .scad model is first exported by OpenSCAD (`openscad -o MODEL.csg`, with
// the -D values), as fabatlas reads it. The tree is the text that export
// writes (grammar: common/scad/src/csg_tree.cc): nodes `name(args) { ... }`
// or `name(args);`, `%`/`*` nodes dropped, `!`/`#` ignored.
//
// Primitives are faceted as OpenSCAD 2021.01 facets them (the rules of
// common/scad/src/primitive_mesh.cc, ported: Fragments from $fn/$fa/$fs,
// sphere rings at (i + 0.5) / rings, cylinder rings, a cone's single tip,
// circles), so both evaluate the same triangles; Manifold takes them as
// meshes in float32. Natively: cube, sphere, cylinder, polyhedron (convex
// faces fanned from their first corner, others ear-clipped; all flipped when
// they enclose a negative volume, as OpenSCAD's clockwise faces do),
// multmatrix, group/union/render/color, difference, intersection, hull,
// minkowski (Manifold's minkowskiSum), resize, import of STL; linear_extrude
// (height, center, twist, slices by OpenSCAD's rule, scale): a straight one
// by Manifold's extrusion, a twisted or scaled one as OpenSCAD's own mesh
// (its side quads split along the shorter diagonal decide the volume);
// rotate_extrude as OpenSCAD's own mesh (its sectors, a full turn starting on
// -x; Manifold's revolve starts on +x and gives nothing for one or two
// sectors); and the 2-D circle, square, polygon (paths, even-odd), 2-D
// booleans, multmatrix, hull and resize. Any other 2-D node (text, offset,
// projection, import of DXF/SVG) is outlined by OpenSCAD before the timing
// (`openscad -o outline.svg` of that subtree alone, read back as even-odd
// loops), as fabatlas does. Any other 3-D node (surface, import of 3MF, OFF,
// AMF, OBJ, ...) is not evaluated: the script names it and exits 3.
// OpenSCAD's behaviour where input is odd: a child of the other dimension
// (3-D under a 2-D operation, 2-D beside 3-D) is dropped, an intersection
// with a 2-D or empty operand is empty, a primitive or transform with a
// non-finite number is dropped, a rotate_extrude across the axis is empty, a
// missing import is empty. Known differences: a linear_extrude scaled to 0
// on an axis (OpenSCAD collapses its top differently), polyhedra that are
// not manifold (Manifold rejects them), minkowski of non-convex parts
// (Manifold's decomposition).
//
// Timing: the evaluation from the CSG text to the final mesh (parse,
// primitives, booleans, getMesh), in process, WASM start-up and OpenSCAD's
// export and outlines excluded; one warm-up, then the median of --repeats
// (at least 5). Prints volume (mm^3), triangles and milliseconds; --json
// also the median CPU milliseconds of the process over the same span
// (process.cpuUsage: user + system; with --single-threaded the evaluation's
// thread is the process's only busy one), the figure to set beside another
// program's thread CPU on a loaded machine.
import Module from 'manifold-3d';
import {execFileSync} from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

// ---- the .csg grammar ----

function parseCsg(text, file) {
  let i = 0, line = 1;
  const fail = (what) => { throw new Error(`${file}:${line}: ${what}`); };
  const skip = () => {
    for (;;) {
      while (i < text.length && /\s/.test(text[i])) { if (text[i] === '\n') ++line; ++i; }
      if (text.startsWith('//', i)) { while (i < text.length && text[i] !== '\n') ++i; continue; }
      if (text.startsWith('/*', i)) {
        const e = text.indexOf('*/', i + 2);
        for (let k = i; k < (e < 0 ? text.length : e); ++k) if (text[k] === '\n') ++line;
        i = e < 0 ? text.length : e + 2;
        continue;
      }
      return;
    }
  };
  const eat = (c) => { skip(); if (text[i] === c) { ++i; return true; } return false; };
  const expect = (c) => { if (!eat(c)) fail(`expected '${c}'`); };
  const ident = () => {
    skip();
    const m = /^[A-Za-z0-9_$]+/.exec(text.slice(i, i + 256));
    if (!m) fail('expected a name');
    i += m[0].length;
    return m[0];
  };
  const value = () => {
    skip();
    const c = text[i];
    if (c === undefined) fail('unexpected end of file');
    if (c === '[') {
      ++i;
      const items = [];
      if (eat(']')) return items;
      do items.push(value()); while (eat(','));
      expect(']');
      return items;
    }
    if (c === '"') {
      let s = '';
      for (++i; i < text.length && text[i] !== '"'; ++i) {
        if (text[i] === '\\') {
          const n = text[++i];
          s += n === 'n' ? '\n' : n === 't' ? '\t' : n === 'r' ? '\r' : n;
        } else s += text[i];
      }
      if (text[i] !== '"') fail('unterminated string');
      ++i;
      return s;
    }
    const m = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?/.exec(text.slice(i, i + 64));
    if (m) { i += m[0].length; return Number(m[0]); }
    const w = ident();
    if (w === 'true' || w === 'false') return w === 'true';
    if (w === 'undef') return undefined;
    if (w === 'inf') return Infinity;
    if (w === 'nan') return NaN;
    fail(`unexpected '${w}' in an argument`);
  };
  const node = () => {
    skip();
    const start = i, at = line;
    let dropped = false;
    while ('!#%*'.includes(text[i]) && i < text.length) { if (text[i] === '%' || text[i] === '*') dropped = true; ++i; }
    const n = {name: ident(), args: {}, positional: [], children: [], line: at};
    expect('(');
    if (!eat(')')) {
      do {
        skip();
        const save = i, saveLine = line;
        let named = false;
        if (/[A-Za-z_$]/.test(text[i])) {
          const key = ident();
          if (eat('=')) { n.args[key] = value(); named = true; } else { i = save; line = saveLine; }
        }
        if (!named) n.positional.push(value());
      } while (eat(','));
      expect(')');
    }
    if (!eat(';')) {
      expect('{');
      while (!eat('}')) {
        if (i >= text.length) fail(`missing '}' of ${n.name}`);
        const c = node();
        if (!c.dropped) n.children.push(c);
      }
    }
    n.dropped = dropped;
    n.source = text.slice(start, i).replace(/^[!#]+/, '');
    return n;
  };
  const root = {name: 'group', args: {}, positional: [], children: [], line: 1};
  skip();
  while (i < text.length) {
    const c = node();
    if (!c.dropped) root.children.push(c);
    skip();
  }
  return root;
}

// ---- OpenSCAD 2021.01's faceting (common/scad/src/primitive_mesh.cc) ----

const sinDeg = (a) => Math.sin(a * Math.PI / 180);
const cosDeg = (a) => Math.cos(a * Math.PI / 180);
const num = (v, d) => (typeof v === 'number' && !Number.isNaN(v) ? v : d);
// OpenSCAD drops a primitive with a non-finite size, radius or point.
const finite = (...xs) => xs.flat(2).every((x) => typeof x !== 'number' || Number.isFinite(x));

// $fn when > 0 (at least 3), else ceil(max(min(360 / $fa, 2 pi r / $fs), 5)); 3 below r ~ 1e-6.
// An infinite $fn gives 3, as OpenSCAD 2021.01's integer conversion does.
function fragments(r, fn, fs, fa) {
  if (r < 1e-6) return 3;
  if (fn > 0) return fn >= 3 && Number.isFinite(fn) ? Math.trunc(fn) : 3;
  return Math.ceil(Math.max(Math.min(360 / fa, r * 2 * Math.PI / fs), 5));
}
const fragmentsOf = (n, r) => fragments(r, num(n.args.$fn, 0), num(n.args.$fs, 2), num(n.args.$fa, 12));

// A triangle mesh {verts: [[x,y,z]], tris: [[a,b,c]]} from polygon faces (fans).
function fanMesh(verts, faces) {
  const tris = [];
  for (const f of faces) for (let k = 1; k + 1 < f.length; ++k) tris.push([f[0], f[k], f[k + 1]]);
  return {verts, tris};
}

function cubeMesh(s, center) {
  const lo = center ? s.map((x) => -x / 2) : [0, 0, 0];
  const verts = [];
  for (let k = 0; k < 8; ++k) verts.push([lo[0] + (k & 1 ? s[0] : 0), lo[1] + (k & 2 ? s[1] : 0), lo[2] + (k & 4 ? s[2] : 0)]);
  return fanMesh(verts, [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]);
}

function sphereMesh(r, n) {
  const rings = Math.trunc((n + 1) / 2), verts = [], faces = [];
  for (let i = 0; i < rings; ++i) {
    const phi = 180 * (i + 0.5) / rings, rr = r * sinDeg(phi), z = r * cosDeg(phi);
    for (let j = 0; j < n; ++j) verts.push([rr * cosDeg(360 * j / n), rr * sinDeg(360 * j / n), z]);
  }
  const at = (ring, j) => ring * n + (j % n);
  faces.push([...Array(n).keys()].map((j) => at(0, j)).reverse());
  faces.push([...Array(n).keys()].map((j) => at(rings - 1, j)));
  for (let i = 0; i + 1 < rings; ++i)
    for (let j = 0; j < n; ++j) faces.push([at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)]);
  return fanMesh(verts, faces);
}

function cylinderMesh(h, r1, r2, center, n) {
  const z1 = center ? -h / 2 : 0, z2 = z1 + h, verts = [], faces = [];
  // A cone's tip is one vertex, as OpenSCAD builds it.
  const ring = (r, z) => {
    const base = verts.length;
    if (r === 0) { verts.push([0, 0, z]); return () => base; }
    for (let j = 0; j < n; ++j) verts.push([r * cosDeg(360 * j / n), r * sinDeg(360 * j / n), z]);
    return (j) => base + (j % n);
  };
  const b = ring(r1, z1), t = ring(r2, z2);
  for (let j = 0; j < n; ++j) {
    const f = [b(j), b(j + 1), t(j + 1), t(j)];
    faces.push(f.filter((v, k) => f.indexOf(v) === k));
  }
  if (r1 > 0) faces.push([...Array(n).keys()].map(b).reverse());
  if (r2 > 0) faces.push([...Array(n).keys()].map(t));
  return fanMesh(verts, faces);
}

const circleLoop = (r, n) => [...Array(n).keys()].map((j) => [r * cosDeg(360 * j / n), r * sinDeg(360 * j / n)]);

// OpenSCAD 2021.01's number of linear_extrude slices without a `slices`
// argument (ExtrudeSlices in primitive_mesh.cc).
function extrudeSlices(rSqr, deltaSqr, height, twist, scale, fn, fs, fa) {
  const kFine = 1e-8;
  twist = Math.abs(twist);
  const uniform = scale[0] === scale[1];
  const diagonal = () => {
    if (Math.sqrt(deltaSqr) < kFine || !Number.isFinite(fn)) return 1;
    if (fn > 0) return Math.max(Math.trunc(fn), 1);
    return Math.max(Math.ceil(Math.sqrt(deltaSqr + height * height) / fs), 1);
  };
  if (twist === 0) return uniform ? 1 : diagonal();
  const twisted = () => {
    const minSlices = Math.max(Math.ceil(twist / 120), 1), r = Math.sqrt(rSqr);
    if (r < kFine || !Number.isFinite(fn)) return minSlices;
    if (fn > 0) return Math.max(Math.ceil(twist * fn / 360), minSlices);
    const rad = twist * Math.PI / 180;
    let length;
    if (!uniform || scale[0] === 1) {
      const c = height / rad;
      length = rad * Math.sqrt(rSqr + c * c);
    } else {
      const sc = scale[0], end = sc > 1 ? rad * sc / (sc - 1) : rad / (1 - sc), start = end - rad, a = r / end;
      const arc = (th) => 0.5 * a * (th * Math.sqrt(1 + th * th) + Math.asinh(th));
      const spiral = arc(end) - arc(start);
      length = Math.sqrt(spiral * spiral + height * height);
    }
    return Math.max(Math.min(Math.ceil(twist / fa), Math.ceil(length / fs)), minSlices);
  };
  return uniform ? twisted() : Math.max(twisted(), diagonal());
}

// Triangles of one polygon face given as 3-D points (indices into pts).
function triangulateFace(pts, ids) {
  if (ids.length === 3) return [ids];
  const nrm = [0, 0, 0];
  for (let k = 0; k < ids.length; ++k) {
    const a = pts[ids[k]], b = pts[ids[(k + 1) % ids.length]];
    nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
    nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
    nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
  }
  const ax = [0, 1, 2].reduce((m, k) => (Math.abs(nrm[k]) > Math.abs(nrm[m]) ? k : m), 0);
  const u = (ax + 1) % 3, v = (ax + 2) % 3, s = nrm[ax] >= 0 ? 1 : -1;
  const p2 = ids.map((id) => [pts[id][u], s * pts[id][v]]);
  const cross = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  // A convex face (in its plane's projection) is a fan from its first
  // corner, as fabatlas's PolyhedronMesh: the split of a non-planar quad
  // decides its volume (issue1867: the fan gives OpenSCAD's); others are
  // ear-clipped.
  const fan = () => ids.slice(1, -1).map((_, k) => [ids[0], ids[k + 1], ids[k + 2]]);
  if (p2.every((_, k) => cross(p2[k], p2[(k + 1) % p2.length], p2[(k + 2) % p2.length]) >= 0)) return fan();
  let idx = [...ids.keys()];
  const tris = [];
  let guard = 0;
  while (idx.length > 3 && guard++ < 4 * ids.length * ids.length) {
    let clipped = false;
    for (let k = 0; k < idx.length; ++k) {
      const a = idx[(k + idx.length - 1) % idx.length], b = idx[k], c = idx[(k + 1) % idx.length];
      if (cross(p2[a], p2[b], p2[c]) <= 0) continue;
      const inside = idx.some((q) => q !== a && q !== b && q !== c && cross(p2[a], p2[b], p2[q]) >= 0 &&
                                     cross(p2[b], p2[c], p2[q]) >= 0 && cross(p2[c], p2[a], p2[q]) >= 0);
      if (inside) continue;
      tris.push([ids[a], ids[b], ids[c]]);
      idx.splice(k, 1);
      clipped = true;
      break;
    }
    if (!clipped) break;
  }
  for (let k = 1; k + 1 < idx.length; ++k) tris.push([ids[idx[0]], ids[idx[k]], ids[idx[k + 1]]]);
  return tris;
}

// linear_extrude of a region as OpenSCAD 2021.01 meshes it
// (LinearExtrudeMesh in primitive_mesh.cc): layer s rotated by
// -twist * s / slices, then scaled; caps triangulated; each side quad split
// along its shorter diagonal (equal ones by the twist's sign, the other way
// on holes).
function linearExtrudeMesh(w, loops, height, center, twist, slices, scale) {
  const points = loops.flat(), n = points.length;
  const caps = w.triangulate(loops);
  const verts = [], tris = [];
  const z0 = center ? -height / 2 : 0;
  for (let s = 0; s <= slices; ++s) {
    const t = s / slices, ang = -twist * t, c = cosDeg(ang), si = sinDeg(ang);
    const sx = 1 + (scale[0] - 1) * t, sy = 1 + (scale[1] - 1) * t;
    for (const [x, y] of points) verts.push([sx * (c * x - si * y), sy * (si * x + c * y), z0 + height * t]);
  }
  for (const [i, j, k] of caps) {
    tris.push([i, k, j]);
    tris.push([slices * n + i, slices * n + j, slices * n + k]);
  }
  const sq = (i, j) => (verts[i][0] - verts[j][0]) ** 2 + (verts[i][1] - verts[j][1]) ** 2;
  let base = 0;
  for (const loop of loops) {
    const k = loop.length;
    let area = 0;
    for (let i = 0; i < k; ++i) area += loop[i][0] * loop[(i + 1) % k][1] - loop[(i + 1) % k][0] * loop[i][1];
    const tieEndUp = (twist < 0) !== (area < 0);
    for (let s = 0; s < slices; ++s)
      for (let i = 0; i < k; ++i) {
        const p1 = s * n + base + i, c1 = s * n + base + (i + 1) % k, p2 = p1 + n, c2 = c1 + n;
        const d1 = sq(c1, p2), d2 = sq(p1, c2), tol = 1e-9 * Math.max(d1, d2);
        const endUp = Math.abs(d1 - d2) <= tol ? tieEndUp : d1 < d2;
        if (endUp) tris.push([p1, c1, p2], [c1, c2, p2]);
        else tris.push([p1, c1, c2], [p1, c2, p2]);
      }
    base += k;
  }
  return {verts, tris};
}

// rotate_extrude of a region as OpenSCAD 2021.01 meshes it
// (RotateExtrudeMesh in primitive_mesh.cc): `sectors` steps through `angle`
// degrees from +x, a full turn from -x (an outline on x < 0 sweeps with its
// negative radii, as OpenSCAD's); open ends capped. Manifold's own revolve
// starts a full turn on +x and gives nothing for one or two sectors.
function rotateExtrudeMesh(w, loops, angle, sectors) {
  const points = loops.flat(), n = points.length, full = Math.abs(angle) >= 360;
  const rings = full ? sectors : sectors + 1, verts = [], tris = [];
  for (let r = 0; r < rings; ++r) {
    const t = full ? 180 + 360 * r / sectors : angle * r / sectors;
    for (const [x, y] of points) verts.push([x * cosDeg(t), x * sinDeg(t), y]);
  }
  let base = 0;
  for (const loop of loops) {
    const k = loop.length;
    for (let r = 0; r < sectors; ++r) {
      const r2 = full ? (r + 1) % sectors : r + 1;
      for (let i = 0; i < k; ++i) {
        const a = r * n + base + i, b = r * n + base + (i + 1) % k, c = r2 * n + base + (i + 1) % k, d = r2 * n + base + i;
        tris.push([a, b, c], [a, c, d]);
      }
    }
    base += k;
  }
  if (!full)
    for (const [i, j, k] of w.triangulate(loops)) tris.push([i, k, j], [sectors * n + i, sectors * n + j, sectors * n + k]);
  return {verts, tris};
}

// resize(newsize, auto): the scale per axis OpenSCAD 2021.01 applies about
// the origin: newsize / size where newsize > 0; an axis with auto set takes
// the largest of those; the rest 1.
function resizeScale(a, box, dims) {
  const size = [...Array(dims).keys()].map((k) => box.max[k] - box.min[k]);
  const want = Array.isArray(a.newsize) ? a.newsize : [];
  const auto = Array.isArray(a.auto) ? a.auto : [...Array(dims)].map(() => a.auto);
  const scale = size.map((sz, k) => (num(want[k], 0) > 0 && sz > 0 ? want[k] / sz : 1));
  const given = scale.filter((_, k) => num(want[k], 0) > 0);
  const autoscale = given.length ? Math.max(...given) : 1;
  return scale.map((x, k) => (!(num(want[k], 0) > 0) && (auto[k] === true || auto[k] === 1) ? autoscale : x));
}

// An STL file (binary, or ASCII) as a mesh, corners with equal coordinates merged.
function readStl(file) {
  const buf = fs.readFileSync(file), verts = [], tris = [], at = new Map();
  const vertex = (x, y, z) => {
    const key = `${x},${y},${z}`;
    if (!at.has(key)) { at.set(key, verts.length); verts.push([x, y, z]); }
    return at.get(key);
  };
  const count = buf.length >= 84 ? buf.readUInt32LE(80) : -1;
  if (count >= 0 && buf.length === 84 + 50 * count) {
    for (let t = 0; t < count; ++t) {
      const o = 84 + 50 * t + 12, c = [0, 1, 2].map((k) => vertex(buf.readFloatLE(o + 12 * k), buf.readFloatLE(o + 12 * k + 4),
                                                                    buf.readFloatLE(o + 12 * k + 8)));
      tris.push(c);
    }
  } else {
    const v = [...buf.toString('latin1').matchAll(/vertex\s+(\S+)\s+(\S+)\s+(\S+)/g)].map((m) => vertex(+m[1], +m[2], +m[3]));
    for (let k = 0; k + 2 < v.length; k += 3) tris.push([v[k], v[k + 1], v[k + 2]]);
  }
  return {verts, tris: tris.filter(([a, b, c]) => a !== b && b !== c && a !== c)};
}

// ---- evaluation with Manifold ----

const DIM2 = new Set(['circle', 'square', 'polygon', 'text', 'offset', 'projection']);
const DIM3 = new Set(['cube', 'sphere', 'cylinder', 'polyhedron', 'surface', 'linear_extrude', 'rotate_extrude']);
const GROUPS = new Set(['group', 'union', 'render', 'color', 'difference', 'intersection', 'hull', 'minkowski',
                        'multmatrix', 'resize']);

// 2 or 3 for a node's dimension, 0 for nothing.
function dimension(n) {
  if (DIM2.has(n.name)) return 2;
  if (DIM3.has(n.name)) return 3;
  if (n.name === 'import') return /\.(dxf|svg)$/i.test(String(n.args.file ?? '')) ? 2 : 3;
  if (GROUPS.has(n.name)) {
    for (const c of n.children) { const d = dimension(c); if (d) return d; }
    return 0;
  }
  return 3;  // unknown: 3-D, and reported as unsupported when evaluated
}

// 2-D nodes evaluated natively (the rest are outlined by OpenSCAD).
const NATIVE2 = new Set(['circle', 'square', 'polygon', 'group', 'union', 'render', 'color', 'difference',
                         'intersection', 'hull', 'multmatrix', 'resize']);

// OpenSCAD's SVG export of a 2-D subtree, read back as loops (y flipped back).
function outlineByOpenScad(n, dir, cache) {
  if (cache.has(n.source)) return cache.get(n.source);
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'manifold-csg-'));
  const prog = path.join(dir, `.manifold-outline-${process.pid}.scad`);
  fs.writeFileSync(prog, n.source + '\n');
  const svg = path.join(tmp, 'outline.svg');
  let loops = [];
  try {
    execFileSync('openscad', ['-o', svg, prog], {stdio: ['ignore', 'ignore', 'pipe']});
    const text = fs.readFileSync(svg, 'utf8');
    for (const m of text.matchAll(/<path[^>]* d="([^"]*)"/g)) {
      let loop = [];
      for (const t of m[1].matchAll(/([MLz])\s*(?:([-+\d.eE]+),([-+\d.eE]+))?/g)) {
        if (t[1] === 'M' && loop.length) { loops.push(loop); loop = []; }
        if (t[1] === 'z') { if (loop.length) loops.push(loop); loop = []; continue; }
        loop.push([Number(t[2]), -Number(t[3])]);
      }
      if (loop.length) loops.push(loop);
    }
  } catch (e) {
    loops = null;  // OpenSCAD gives no outline: an empty 2-D result
  } finally {
    fs.rmSync(prog, {force: true});
    fs.rmSync(tmp, {recursive: true, force: true});
  }
  cache.set(n.source, loops);
  return loops;
}

// Walks the tree once, before timing, collecting what is not native:
// outlines for 2-D nodes (by OpenSCAD), names of 3-D nodes Manifold does not do.
function prepare(n, dim2, dir, outlines, report) {
  if (dim2) {
    if (!NATIVE2.has(n.name)) {
      report.outlined.add(n.name);
      outlineByOpenScad(n, dir, outlines);
      return;
    }
    for (const c of n.children) if (dimension(c) === 2) prepare(c, true, dir, outlines, report);
    return;
  }
  if (n.name === 'linear_extrude' || n.name === 'rotate_extrude') {
    for (const c of n.children) if (dimension(c) === 2) prepare(c, true, dir, outlines, report);
    return;
  }
  if (GROUPS.has(n.name)) {
    const d = dimension(n);
    for (const c of n.children) if (dimension(c) === d) prepare(c, d === 2, dir, outlines, report);
    return;
  }
  if (['cube', 'sphere', 'cylinder', 'polyhedron'].includes(n.name)) return;
  if (n.name === 'import' && /\.stl$/i.test(String(n.args.file ?? ''))) return;
  report.unsupported.add(`${n.name} (CSG line ${n.line})`);
}

class Evaluator {
  constructor(wasm, outlines, dir) {
    this.w = wasm;
    this.dir = dir;
    this.outlines = outlines;
    this.live = [];
  }

  keep(x) { this.live.push(x); return x; }

  release() { for (const x of this.live) x.delete(); this.live = []; }

  mesh3(m) {
    // Orientation: OpenSCAD's faces are clockwise from outside; flip all when
    // the signed volume is negative.
    let vol = 0;
    for (const [a, b, c] of m.tris) {
      const p = m.verts[a], q = m.verts[b], r = m.verts[c];
      vol += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0]);
    }
    const vp = new Float32Array(m.verts.length * 3), tv = new Uint32Array(m.tris.length * 3);
    m.verts.forEach((v, k) => vp.set(v, 3 * k));
    m.tris.forEach((t, k) => tv.set(vol < 0 ? [t[0], t[2], t[1]] : t, 3 * k));
    const mesh = new this.w.Mesh({numProp: 3, vertProperties: vp, triVerts: tv});
    mesh.merge();
    return this.keep(new this.w.Manifold(mesh));
  }

  empty3() { return this.keep(new this.w.Manifold(new this.w.Mesh({numProp: 3, vertProperties: new Float32Array(0), triVerts: new Uint32Array(0)}))); }

  empty2() { return this.keep(new this.w.CrossSection([[[0, 0], [0, 0], [0, 0]]], 'Positive')); }

  // 3-D node -> Manifold.
  eval3(n) {
    const {Manifold} = this.w;
    const a = n.args;
    switch (n.name) {
      case 'cube': {
        let s = a.size ?? 1;
        s = Array.isArray(s) ? s.map((x) => num(x, 1)) : [num(s, 1), num(s, 1), num(s, 1)];
        if (s.length < 3 || s.some((x) => !(x > 0) || !Number.isFinite(x))) return this.empty3();
        return this.mesh3(cubeMesh(s, a.center === true));
      }
      case 'sphere': {
        const r = num(a.r, 1);
        return r > 0 && Number.isFinite(r) ? this.mesh3(sphereMesh(r, fragmentsOf(n, r))) : this.empty3();
      }
      case 'cylinder': {
        const h = num(a.h, 1), r1 = num(a.r1, 1), r2 = num(a.r2, 1);
        if (!(h > 0) || r1 < 0 || r2 < 0 || (r1 === 0 && r2 === 0) || !finite(h, r1, r2)) return this.empty3();
        return this.mesh3(cylinderMesh(h, r1, r2, a.center === true, fragmentsOf(n, Math.max(r1, r2))));
      }
      case 'polyhedron': {
        if (!finite(a.points ?? [])) return this.empty3();
        const pts = (a.points ?? []).map((p) => [num(p[0], 0), num(p[1], 0), num(p[2], 0)]);
        const faces = a.faces ?? a.triangles ?? [];
        const tris = [];
        for (const f of faces) if (f.length >= 3) tris.push(...triangulateFace(pts, f));
        return tris.length ? this.mesh3({verts: pts, tris}) : this.empty3();
      }
      case 'multmatrix': {
        const m = a.m ?? n.positional[0];
        if (!finite(m)) return this.empty3();  // OpenSCAD drops an object under a non-finite transform
        const inner = this.union3(n.children);
        return this.keep(inner.transform([m[0][0], m[1][0], m[2][0], 0, m[0][1], m[1][1], m[2][1], 0,
                                          m[0][2], m[1][2], m[2][2], 0, m[0][3], m[1][3], m[2][3], 1]));
      }
      case 'group': case 'union': case 'render': case 'color':
        return this.union3(n.children);
      case 'difference': case 'intersection': {
        // An intersection with an operand that is not 3-D (2-D, or no
        // geometry: `render();`) is empty in OpenSCAD 2021.01.
        if (n.name === 'intersection' && n.children.some((c) => dimension(c) !== 3)) return this.empty3();
        const parts = n.children.filter((c) => dimension(c) === 3).map((c) => this.eval3(c));
        if (!parts.length) return this.empty3();
        if (n.name === 'intersection') return this.keep(Manifold.intersection(parts));
        if (parts.length === 1) return parts[0];
        return this.keep(parts[0].subtract(this.keep(Manifold.union(parts.slice(1)))));
      }
      case 'hull': {
        const parts = n.children.filter((c) => dimension(c) === 3).map((c) => this.eval3(c));
        return parts.length ? this.keep(Manifold.hull(parts)) : this.empty3();
      }
      case 'minkowski': {
        const parts = n.children.filter((c) => dimension(c) === 3).map((c) => this.eval3(c));
        if (!parts.length) return this.empty3();
        return parts.slice(1).reduce((acc, p) => this.keep(acc.minkowskiSum(p)), parts[0]);
      }
      case 'linear_extrude': {
        const cs = this.union2(n.children);
        const h = num(a.height, 100), twist = num(a.twist, 0);
        if (!(h > 0) || cs.isEmpty()) return this.empty3();  // Manifold: an empty extrusion is an invalid construction
        const sc = (Array.isArray(a.scale) ? [num(a.scale[0], 1), num(a.scale[1], 1)] : [num(a.scale, 1), num(a.scale, 1)])
          .map((x) => Math.max(x, 0));  // OpenSCAD 2021.01 takes a negative scale as 0
        let slices = Math.trunc(num(a.slices, 0));
        if (slices <= 0) {
          let rSqr = 0, deltaSqr = 0;
          for (const loop of cs.toPolygons())
            for (const [x, y] of loop) {
              rSqr = Math.max(rSqr, x * x + y * y);
              const dx = x * (1 - sc[0]), dy = y * (1 - sc[1]);
              deltaSqr = Math.max(deltaSqr, dx * dx + dy * dy);
            }
          slices = extrudeSlices(rSqr, deltaSqr, h, twist, sc, num(a.$fn, 0), num(a.$fs, 2), num(a.$fa, 12));
        }
        if (twist === 0 && sc[0] === 1 && sc[1] === 1) return this.keep(cs.extrude(h, 0, 0, [1, 1], a.center === true));
        // Twisted or scaled: the walls decide the volume, so OpenSCAD's mesh.
        return this.mesh3(linearExtrudeMesh(this.w, cs.toPolygons(), h, a.center === true, twist, slices, sc));
      }
      case 'rotate_extrude': {
        let cs = this.union2(n.children);
        if (cs.isEmpty()) return this.empty3();
        let b = cs.bounds();
        // OpenSCAD 2021.01 rejects an outline on both sides of the axis (an
        // error; the node is empty).
        if (b.min[0] < 0 && b.max[0] > 0) return this.empty3();
        const angle = Number.isFinite(a.angle) ? Math.max(-360, Math.min(360, a.angle)) : 360;
        if (angle === 0) return this.empty3();
        // OpenSCAD 2021.01: fragments from the largest |x|, truncated to the angle's share.
        const r = Math.max(-b.min[0], b.max[0]);
        const sectors = Math.trunc(Math.max(fragmentsOf(n, r) * Math.abs(angle) / 360, 1));
        return this.mesh3(rotateExtrudeMesh(this.w, cs.toPolygons(), angle, sectors));
      }
      case 'resize': {
        const inner = this.union3(n.children);
        return inner.isEmpty() ? inner : this.keep(inner.scale(resizeScale(a, inner.boundingBox(), 3)));
      }
      case 'import': {
        const file = path.resolve(this.dir, String(a.file));
        if (!fs.existsSync(file)) return this.empty3();  // OpenSCAD warns and imports nothing
        const m = readStl(file);
        return m.tris.length ? this.mesh3(m) : this.empty3();
      }
      default:
        throw new Error(`${n.name} (CSG line ${n.line}): not evaluated by this script`);
    }
  }

  union3(children) {
    const parts = children.filter((c) => dimension(c) === 3).map((c) => this.eval3(c));
    if (!parts.length) return this.empty3();
    return parts.length === 1 ? parts[0] : this.keep(this.w.Manifold.union(parts));
  }

  // 2-D node -> CrossSection.
  eval2(n) {
    const {CrossSection} = this.w;
    const a = n.args;
    if (!NATIVE2.has(n.name)) {
      const loops = this.outlines.get(n.source);
      return loops && loops.length ? this.keep(new CrossSection(loops, 'EvenOdd')) : this.empty2();
    }
    switch (n.name) {
      case 'circle': {
        const r = num(a.r, 1);
        return r > 0 ? this.keep(new CrossSection([circleLoop(r, fragmentsOf(n, r))], 'Positive')) : this.empty2();
      }
      case 'square': {
        let s = a.size ?? 1;
        s = Array.isArray(s) ? [num(s[0], 1), num(s[1], 1)] : [num(s, 1), num(s, 1)];
        if (!(s[0] > 0 && s[1] > 0)) return this.empty2();
        const x0 = a.center === true ? -s[0] / 2 : 0, y0 = a.center === true ? -s[1] / 2 : 0;
        return this.keep(new CrossSection([[[x0, y0], [x0 + s[0], y0], [x0 + s[0], y0 + s[1]], [x0, y0 + s[1]]]], 'Positive'));
      }
      case 'polygon': {
        const pts = (a.points ?? []).map((p) => [num(p[0], 0), num(p[1], 0)]);
        const paths = Array.isArray(a.paths) ? a.paths : [[...pts.keys()]];
        const loops = paths.map((p) => p.map((k) => pts[k]).filter(Boolean)).filter((l) => l.length >= 3);
        return loops.length ? this.keep(new CrossSection(loops, 'EvenOdd')) : this.empty2();
      }
      case 'multmatrix': {
        const m = a.m ?? n.positional[0];
        if (!finite(m)) return this.empty2();
        return this.keep(this.union2(n.children).transform([m[0][0], m[1][0], 0, m[0][1], m[1][1], 0, m[0][3], m[1][3], 1]));
      }
      case 'group': case 'union': case 'render': case 'color':
        return this.union2(n.children);
      case 'difference': case 'intersection': {
        const parts = n.children.filter((c) => dimension(c) === 2).map((c) => this.eval2(c));
        if (!parts.length) return this.empty2();
        if (n.name === 'intersection') return this.keep(CrossSection.intersection(parts));
        if (parts.length === 1) return parts[0];
        return this.keep(parts[0].subtract(this.keep(CrossSection.union(parts.slice(1)))));
      }
      case 'hull': {
        const parts = n.children.filter((c) => dimension(c) === 2).map((c) => this.eval2(c));
        return parts.length ? this.keep(CrossSection.hull(parts)) : this.empty2();
      }
      case 'resize': {
        const inner = this.union2(n.children);
        return inner.isEmpty() ? inner : this.keep(inner.scale(resizeScale(a, inner.bounds(), 2)));
      }
    }
    throw new Error(`${n.name} (CSG line ${n.line}): not evaluated by this script`);
  }

  union2(children) {
    const parts = children.filter((c) => dimension(c) === 2).map((c) => this.eval2(c));
    if (!parts.length) return this.empty2();
    return parts.length === 1 ? parts[0] : this.keep(this.w.CrossSection.union(parts));
  }
}

// ---- the command ----

function writeStl(mesh, file) {
  const n = mesh.triVerts.length / 3, p = mesh.numProp, v = mesh.vertProperties;
  const buf = Buffer.alloc(84 + 50 * n);
  buf.writeUInt32LE(n, 80);
  for (let t = 0; t < n; ++t)
    for (let c = 0; c < 3; ++c)
      for (let k = 0; k < 3; ++k) buf.writeFloatLE(v[mesh.triVerts[3 * t + c] * p + k], 84 + 50 * t + 12 + 12 * c + 4 * k);
  fs.writeFileSync(file, buf);
}

async function main() {
  const argv = process.argv.slice(2);
  let model = null, repeats = 5, stl = null, json = false;
  const defines = [];
  for (let k = 0; k < argv.length; ++k) {
    if (argv[k] === '--repeats') repeats = Math.max(5, Number(argv[++k]));
    else if (argv[k] === '--stl') stl = argv[++k];
    else if (argv[k] === '--json') json = true;
    else if (argv[k] === '-D') defines.push('-D', argv[++k]);
    else if (!model) model = argv[k];
    else { console.error(`manifold_csg: unexpected argument ${argv[k]}`); process.exit(2); }
  }
  if (!model) {
    console.error('usage: node bench/scad/manifold_csg.mjs MODEL.csg|MODEL.scad [--repeats 5] [--stl OUT.stl] [--json] [-D name=value ...]');
    process.exit(2);
  }
  let csgFile = model;
  if (model.endsWith('.scad')) {
    const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'manifold-csg-'));
    csgFile = path.join(tmp, 'model.csg');
    try {
      execFileSync('openscad', ['-o', csgFile, ...defines, model], {stdio: ['ignore', 'ignore', 'pipe']});
    } catch (e) {
      console.error(`manifold_csg: ${model}: OpenSCAD could not export the CSG tree: ${String(e.stderr).trim().split('\n').pop()}`);
      process.exit(2);
    }
  }
  let text;
  try {
    text = fs.readFileSync(csgFile, 'utf8');
  } catch (e) {
    console.error(`manifold_csg: ${csgFile}: cannot read (${e.code})`);
    process.exit(2);
  }
  const dir = path.dirname(path.resolve(model));
  const report = {outlined: new Set(), unsupported: new Set()};
  const outlines = new Map();
  let tree;
  try {
    tree = parseCsg(text, csgFile);
  } catch (e) {
    console.error(`manifold_csg: ${e.message}`);
    process.exit(2);
  }
  prepare(tree, false, dir, outlines, report);
  const out = {model, outlined_by_openscad: [...report.outlined], unsupported: [...report.unsupported]};
  if (report.unsupported.size) {
    console.log(json ? JSON.stringify(out) : `${model}: not evaluated: ${out.unsupported.join(', ')}`);
    process.exit(3);
  }

  const wasm = await Module();
  wasm.setup();
  const ev = new Evaluator(wasm, outlines, dir);
  const run = () => {
    const c = process.cpuUsage();
    const t = process.hrtime.bigint();
    const m = ev.union3(parseCsg(text, csgFile).children);
    const mesh = m.getMesh();
    const ms = Number(process.hrtime.bigint() - t) / 1e6;
    const cpu = process.cpuUsage(c);
    return {ms, cpuMs: (cpu.user + cpu.system) / 1e3, m, mesh};
  };
  const times = [], cpuTimes = [];
  let last;
  try {
    for (let k = 0; k <= repeats; ++k) {
      if (last) ev.release();
      last = run();
      if (k > 0) {  // the first is the warm-up
        times.push(last.ms);
        cpuTimes.push(last.cpuMs);
      }
    }
  } catch (e) {
    out.error = String(e.message ?? e);
    if (process.env.MANIFOLD_CSG_DEBUG) console.error(e.stack);
    console.log(json ? JSON.stringify(out) : `${model}: Manifold failed: ${out.error}`);
    process.exit(3);
  }
  if (process.env.MANIFOLD_CSG_DEBUG) console.error(times.map((x) => x.toFixed(1)).join(" "));
  const medianOf = (xs) => {
    const v = [...xs].sort((x, y) => x - y);
    return v.length % 2 ? v[(v.length - 1) / 2] : (v[v.length / 2 - 1] + v[v.length / 2]) / 2;
  };
  const median = medianOf(times);
  if (last.m.status() !== 'NoError') {
    out.error = `Manifold's result: ${last.m.status()}`;
    console.log(json ? JSON.stringify(out) : `${model}: Manifold failed: ${out.error}`);
    process.exit(3);
  }
  Object.assign(out, {volume: last.m.volume(), triangles: last.m.numTri(), ms_median: median, ms: times,
                      cpu_ms_median: medianOf(cpuTimes), cpu_ms: cpuTimes});
  if (stl) writeStl(last.mesh, stl);
  ev.release();
  if (json) console.log(JSON.stringify(out));
  else console.log(`${model}: volume ${out.volume.toFixed(3)} mm^3, ${out.triangles} triangles, ${median.toFixed(2)} ms ` +
                   `(median of ${times.length} after a warm-up; ${times.map((x) => x.toFixed(1)).join(' ')})` +
                   (out.outlined_by_openscad.length ? `; outlined by OpenSCAD: ${out.outlined_by_openscad.join(', ')}` : ''));
}

main();
