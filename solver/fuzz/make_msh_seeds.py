"""Writes the gmsh-generated seeds corpus/fuzz_gmsh/gen2vol*.msh (gmsh 4.8 Python API, Debian's
python3-gmsh; run with /usr/bin/python3 from solver/fuzz/): two boxes sharing a face (two
volume entities), coarse, saved with every element dimension (points, lines, triangles, tets)
as MSH 2.2 ASCII/binary and MSH 4.1 ASCII/binary with parametric node coordinates."""
import gmsh

gmsh.initialize([], False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("gen2vol")
gmsh.model.occ.addBox(0, 0, 0, 1, 0.5, 0.4)
gmsh.model.occ.addBox(1, 0, 0, 0.5, 0.5, 0.4)
gmsh.model.occ.fragment([(3, 1)], [(3, 2)])
gmsh.model.occ.synchronize()
gmsh.option.setNumber("Mesh.MeshSizeMin", 0.35)
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.35)
gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
gmsh.option.setNumber("General.NumThreads", 1)
gmsh.model.mesh.generate(3)
gmsh.option.setNumber("Mesh.SaveAll", 1)
for version, binary, parametric, name in [(2.2, 0, 0, "gen2vol22.msh"), (2.2, 1, 0, "gen2vol22bin.msh"),
                                          (4.1, 0, 1, "gen2vol41param.msh"),
                                          (4.1, 1, 1, "gen2vol41parambin.msh")]:
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.option.setNumber("Mesh.SaveParametric", parametric)
    gmsh.write("corpus/fuzz_gmsh/" + name)
gmsh.finalize()
