#!/usr/bin/env python3
"""PrusaSlicer slices what fabatlas exports of real OpenSCAD models (issue 32).

Models nobody on the team wrote: OpenSCAD's colour regression model
(openscad-testing-data, features/color-tests.scad: nine cubes coloured by
vector, name, alpha, none, and one colour inside another) and MCAD's stepper
motor (openscad-mcad, stepper.scad's motor(Nema17): a black body and an
aluminium axle, colours from MCAD's materials.scad). For each,
`fabatlas eval --mesh X.3mf` writes one object per part; the test asserts

  - the 3MF's objects are the model's parts and their basematerials colours
    are OpenSCAD's own: for color-tests the innermost color() OpenSCAD 2021.01
    writes per top-level statement in its .csg export, for the motor the
    vectors of MCAD's materials.scad;
  - `prusa-slicer --info` (PrusaSlicer 2.5) reports every object manifold,
    with no repair (no degenerate_facets / edges_fixed / facets_removed /
    facets_reversed / backwards_edges line), and the objects' volumes add up
    to the sample's;
  - `prusa-slicer --export-gcode` slices the 3MF, the whole STL and one
    part's STL (`--part`);
  - a color() with an unknown name is one line `FILE:LINE: color("NAME"): ...`
    and exit status 2.

Needs prusa-slicer and openscad (ops/install-deps.sh); exits 77 (skipped)
without them. About 20 s on 2 cores.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile

BIN = os.path.join(os.environ.get("FABATLAS_BIN_DIR", "build/bin"), "fabatlas")
FEATURES = "/usr/share/openscad/testdata/scad/3D/features"
MCAD = "/usr/share/openscad/libraries/MCAD"
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def run(args, **kw):
    return subprocess.run(args, capture_output=True, text=True, timeout=300, **kw)


def design(dir, name, model):
    path = os.path.join(dir, name + ".yaml")
    with open(path, "w") as f:
        f.write("name: %s\nvoxel_size: 0.5\nparameters: {unused: {type: integer, min: 0, max: 1, default: 0}}\n"
                "tree: {op: openscad, file: '%s'}\nproperties: [volume]\n" % (name, model))
    return path


def hex_colour(rgba):
    return "#" + "".join("%02X" % int(min(1, max(0, c)) * 255 + 0.5) for c in rgba)


def three_mf_objects(path):
    """(name, displaycolor or None) per object, in order."""
    xml = zipfile.ZipFile(path).read("3D/3dmodel.model").decode()
    colours = re.findall(r'<base name="[^"]*" displaycolor="([^"]+)"/>', xml)
    out = []
    for attrs in re.findall(r"<object ([^>]*)>", xml):
        name = re.search(r'name="([^"]*)"', attrs).group(1)
        pindex = re.search(r'pindex="(\d+)"', attrs)
        out.append((name, colours[int(pindex.group(1))] if pindex else None))
    return out


def slicer_info(path):
    """prusa-slicer --info: one dict per object."""
    r = run(["prusa-slicer", "--loglevel", "1", "--info", path])
    check(r.returncode == 0, "prusa-slicer --info %s exits 0 (%s)" % (os.path.basename(path), r.stderr.strip()[-200:]))
    objects = []
    for line in r.stdout.splitlines():
        if line == "[%s]" % os.path.basename(path):
            objects.append({})
        elif "=" in line and objects:
            key, value = line.split("=", 1)
            objects[-1][key.strip()] = value.strip()
    return objects


def sliced(path, dir):
    gcode = os.path.join(dir, os.path.basename(path) + ".gcode")
    r = run(["prusa-slicer", "--loglevel", "1", "--export-gcode", path, "-o", gcode])
    layers = 0
    if os.path.exists(gcode):
        layers = sum(1 for line in open(gcode) if line.startswith(";LAYER_CHANGE"))
    check(r.returncode == 0 and layers > 0,
          "prusa-slicer --export-gcode %s: %d layers (%s)" % (os.path.basename(path), layers, r.stderr.strip()[-200:]))


REPAIRS = ("degenerate_facets", "edges_fixed", "facets_removed", "facets_added", "facets_reversed", "backwards_edges")


def manifold_without_repairs(info, what):
    check(len(info) > 0 and all(o.get("manifold") == "yes" for o in info), what + ": every object manifold")
    repaired = [k for o in info for k in o if k in REPAIRS and o[k] not in ("0", "")]
    check(not repaired, what + ": no repairs (%s)" % ", ".join(repaired))


def eval_parts(yaml, out):
    r = run([BIN, "eval", yaml, "--json", "--parts", "--mesh", out])
    check(r.returncode == 0, "fabatlas eval %s --mesh %s (%s)" % (os.path.basename(yaml), os.path.basename(out), r.stderr.strip()))
    return json.loads(r.stdout) if r.returncode == 0 else {"parts": [], "properties": {}}


def openscad_colours(model, dir):
    """OpenSCAD's own .csg: per top-level statement the innermost colour it resolved."""
    csg = os.path.join(dir, "peer.csg")
    subprocess.run(["openscad", "--quiet", "-o", csg, model], cwd=os.path.dirname(model), check=True, timeout=120)
    out = []
    for line in open(csg):
        if not line.strip():
            continue
        if not line.startswith(("\t", "}")):
            out.append(None)
        m = re.search(r"color\(\[([^\]]*)\]\)", line)
        if m and not m.group(1).startswith("-1"):
            out[-1] = [float(x) for x in m.group(1).split(",")]
    return out


def main():
    if not shutil.which("prusa-slicer") or not shutil.which("openscad"):
        print("prusa-slicer or openscad is not installed (ops/install-deps.sh)")
        return 77
    if not os.path.exists(os.path.join(FEATURES, "color-tests.scad")) or not os.path.exists(MCAD):
        print("openscad-testing-data or openscad-mcad is not installed")
        return 77
    dir = tempfile.mkdtemp(prefix="slice-parts-")

    # 1. OpenSCAD's colour regression model.
    model = os.path.join(FEATURES, "color-tests.scad")
    j = eval_parts(design(dir, "colours", model), os.path.join(dir, "colours.3mf"))
    objects = three_mf_objects(os.path.join(dir, "colours.3mf"))
    peer = openscad_colours(model, dir)
    check([o[0] for o in objects] == [p["name"] for p in j["parts"]], "the 3MF's objects are the parts: %s" % objects)
    for name, colour in objects:
        theirs = peer[int(name[4:]) - 1]
        check(colour == (hex_colour(theirs) if theirs else None),
              "%s: displaycolor %s, OpenSCAD's color() %s" % (name, colour, theirs))
    check(len(objects) == 9, "nine cubes, nine objects (the two empty color() statements make none)")
    info = slicer_info(os.path.join(dir, "colours.3mf"))
    check(len(info) == 9, "PrusaSlicer reads 9 objects")
    manifold_without_repairs(info, "colours.3mf")
    volumes = sum(float(o["volume"]) for o in info)
    check(abs(volumes - 9000) < 0.01, "the objects' volumes add up to nine 10 mm cubes: %.4f" % volumes)
    sliced(os.path.join(dir, "colours.3mf"), dir)

    # 2. MCAD's stepper motor: a black body and an aluminium axle.
    motor = os.path.join(dir, "motor.scad")
    with open(motor, "w") as f:
        f.write("include <MCAD/stepper.scad>\nmotor(Nema17);\n")
    yaml = design(dir, "motor", motor)
    j = eval_parts(yaml, os.path.join(dir, "motor.3mf"))
    materials = open(os.path.join(MCAD, "materials.scad")).read()

    def material(name):
        return [float(x) for x in re.search(name + r"\s*=\s*\[([^\]]*)\]", materials).group(1).split(",")] + [1]

    objects = three_mf_objects(os.path.join(dir, "motor.3mf"))
    check(sorted(c for _, c in objects) == sorted([hex_colour(material("BlackPaint")), hex_colour(material("Aluminum"))]),
          "the motor's colours are MCAD's BlackPaint and Aluminum: %s" % objects)
    info = slicer_info(os.path.join(dir, "motor.3mf"))
    check(len(info) == 2, "PrusaSlicer reads 2 objects")
    manifold_without_repairs(info, "motor.3mf")
    volumes = sum(float(o["volume"]) for o in info)
    whole = j["properties"].get("volume", 0)
    check(abs(volumes - whole) < 1e-4 * whole, "the objects add up to the sample's volume: %.2f / %.2f mm^3" % (volumes, whole))
    sliced(os.path.join(dir, "motor.3mf"), dir)
    for args, out in (([], "motor.stl"), (["--part", objects[0][0]], "motor-part.stl")):
        r = run([BIN, "eval", yaml, "--mesh", os.path.join(dir, out)] + args)
        check(r.returncode == 0, "fabatlas eval --mesh %s %s" % (out, " ".join(args)))
        manifold_without_repairs(slicer_info(os.path.join(dir, out)), out)
        sliced(os.path.join(dir, out), dir)

    # 3. An unknown colour name: one line, exit 2.
    bad = os.path.join(dir, "bad.scad")
    with open(bad, "w") as f:
        f.write("cube(1);\ncolor(\"reddish\") sphere(1);\n")
    r = run([BIN, "eval", design(dir, "bad", bad)])
    lines = r.stderr.strip().splitlines()
    check(r.returncode == 2 and len(lines) == 1 and (bad + ':2: color("reddish"): unknown colour name') in lines[0],
          "unknown colour: exit %d, %s" % (r.returncode, lines))

    if not failures:
        shutil.rmtree(dir)
    print("%d failures" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
