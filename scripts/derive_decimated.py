#!/usr/bin/env python3
"""Derives the two decimated models of data/models.json byte for byte: stanford-bunny_39k from
stanford-bunny.obj and igea_67k from igea.obj, by quadric decimation with PyPI
fast-simplification 0.2.0 (agg=7) on float64 positions, written with C's %g.

    python3 -m pip install numpy fast-simplification==0.2.0
    python3 scripts/derive_decimated.py stanford-bunny_39k [MODELS_DIR]

MODELS_DIR (default: $VISFIELD_MODELS, else the per-user folder, else data/models/) must hold
the source model (`experiment models fetch stanford-bunny` or `igea`); the result is checked
against the sha256 in data/models.json and written there atomically, or nothing is written.
"""
import hashlib
import json
import os
import sys
from pathlib import Path

RECIPES = {
    "stanford-bunny_39k": ("stanford-bunny.obj", 0.440044,
                           "# Stanford bunny decimated by us from stanford-bunny.obj to the paper's "
                           "38,889-triangle size (fast-simplification 0.2.0, quadric decimation, "
                           "agg=7, target_reduction=0.440044)"),
    "igea_67k": ("igea.obj", 0.75,
                 "# Igea decimated by us from igea.obj to the paper's 67,170-triangle size "
                 "(fast-simplification 0.2.0, quadric decimation, agg=7, target_reduction=0.750000)"),
}


def default_dir(root):
    if os.environ.get("VISFIELD_MODELS"):
        return Path(os.environ["VISFIELD_MODELS"])
    base = os.environ.get("XDG_DATA_HOME") or (
        os.environ.get("HOME") and os.path.join(os.environ["HOME"], ".local/share"))
    return Path(base) / "visfield/models" if base else root / "data/models"


def main():
    if len(sys.argv) not in (2, 3) or sys.argv[1] not in RECIPES:
        sys.exit(f"usage: {sys.argv[0]} {{{'|'.join(RECIPES)}}} [MODELS_DIR]")
    import numpy as np
    import fast_simplification

    name = sys.argv[1]
    root = Path(__file__).resolve().parent.parent
    folder = Path(sys.argv[2]) if len(sys.argv) == 3 else default_dir(root)
    registry = {m["name"]: m for m in json.loads((root / "data/models.json").read_text())["models"]}
    source, reduction, header = RECIPES[name]
    src = folder / source
    if not src.is_file():
        sys.exit(f"{src}: missing; `experiment models fetch {Path(source).stem}` first")
    want = registry[Path(source).stem]["sha256"]
    if hashlib.sha256(src.read_bytes()).hexdigest() != want:
        sys.exit(f"{src}: sha256 is not data/models.json's {want}")
    vertices, faces = [], []
    for line in src.open():
        if line.startswith("v "):
            vertices.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            idx = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
            faces.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    points, tris = fast_simplification.simplify(
        np.array(vertices, dtype=np.float64), np.array(faces, dtype=np.int32),
        target_reduction=reduction, agg=7)
    text = header + "\n" + "".join("v %g %g %g\n" % tuple(p) for p in points) + "".join(
        "f %d %d %d\n" % tuple(int(i) + 1 for i in t) for t in tris)
    data = text.encode()
    entry = registry[name]
    got = hashlib.sha256(data).hexdigest()
    if got != entry["sha256"]:
        sys.exit(f"{name}: derived sha256 {got}, data/models.json's is {entry['sha256']}: "
                 "nothing written (another fast-simplification or numpy build?)")
    target = folder / entry["file"]
    tmp = folder / f".{entry['file']}.tmp-{os.getpid()}"
    tmp.write_bytes(data)
    os.replace(tmp, target)
    print(f"derived {name} into {target} ({len(data)} bytes, sha256 {got})")


if __name__ == "__main__":
    main()
