// Unstructured tetrahedral beam 1.0 x 0.1 x 0.1 for the cantilever_exact case.
// Regenerate beam.msh with:  gmsh -3 beam.geo -o beam.msh   (gmsh 4.8.4, Debian bookworm)
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1.0, 0.1, 0.1};
Physical Volume("beam", 1) = {1};
Mesh.CharacteristicLengthMin = 0.025;
Mesh.CharacteristicLengthMax = 0.025;
Mesh.Algorithm3D = 1;        // Delaunay
Mesh.Optimize = 1;
Mesh.RandomSeed = 1;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
