#!/usr/bin/env python3
"""A scene whose meshes need gmsh (shogi pieces, .geo-free generators) made runnable where gmsh
is missing (the GPU machines): every body's mesh is exported here by `qdemsph mesh` (world
coordinates, translate/rotate applied) and the scene refers to those .msh files instead.
The run is the same bit for bit (checked on the shogi chain: identical probes).

  ci/gpu/premesh.py QDEMSPH SCENE OUTDIR [--set key=value ...]
writes OUTDIR/scene.yaml and OUTDIR/meshes/<body>.msh (overrides apply before meshing)."""
import argparse
import subprocess
from pathlib import Path

import yaml


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("qdemsph")
    ap.add_argument("scene", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--set", action="append", default=[], dest="sets")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    sets = [x for s in a.sets for x in ("--set", s)]
    subprocess.run([a.qdemsph, "mesh", str(a.scene), "-o", str(a.out / "meshes"), *sets], check=True,
                   stdout=subprocess.DEVNULL)
    # The overridden scene as the solver reads it: apply the same --set values to a copy.
    scene = yaml.safe_load(a.scene.read_text())
    for s in a.sets:
        key, value = s.split("=", 1)
        node, parts = scene, key.split(".")
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = yaml.safe_load(value)
        else:
            node[last] = yaml.safe_load(value)
    for b in scene.get("bodies", []):
        b["mesh"] = {"type": "gmsh", "file": f"meshes/{b['name']}.msh"}
    (a.out / "scene.yaml").write_text(f"# {a.scene} premeshed by ci/gpu/premesh.py {' '.join(a.sets)}\n"
                                      + yaml.safe_dump(scene, sort_keys=False, width=120))
    print(a.out / "scene.yaml")


if __name__ == "__main__":
    main()
