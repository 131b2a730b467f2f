#!/usr/bin/env python3
"""A scene whose meshes need gmsh (shogi pieces, .geo-free generators) made runnable where gmsh
is missing (the GPU machines): every body's mesh is exported here by `qdemsph mesh` (world
coordinates, translate/rotate applied) and the scene refers to those .msh files instead.
The run is the same bit for bit (checked on the shogi chain: identical probes).

  ci/gpu/premesh.py QDEMSPH SCENE OUTDIR
writes OUTDIR/scene.yaml and OUTDIR/meshes/<body>.msh. Run-time overrides (`--set`) go to the
run; mesh parameters belong in the scene (e.g. make_yade_chain.py --mesh-size)."""
import argparse
import subprocess
from pathlib import Path

import yaml


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("qdemsph")
    ap.add_argument("scene", type=Path)
    ap.add_argument("out", type=Path)
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    subprocess.run([a.qdemsph, "mesh", str(a.scene), "-o", str(a.out / "meshes")], check=True,
                   stdout=subprocess.DEVNULL)
    scene = yaml.safe_load(a.scene.read_text())
    for b in scene.get("bodies", []):
        b["mesh"] = {"type": "gmsh", "file": f"meshes/{b['name']}.msh"}
    (a.out / "scene.yaml").write_text(f"# {a.scene} premeshed by ci/gpu/premesh.py\n"
                                      + yaml.safe_dump(scene, sort_keys=False, width=120))
    print(a.out / "scene.yaml")


if __name__ == "__main__":
    main()
