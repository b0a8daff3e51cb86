// full ball for the free-free modal check (second-order tetrahedra, C3D10)
SetFactory("OpenCASCADE");
R = 0.25;
If (!Exists(h)) h = 0.05; EndIf
Sphere(1) = {0, 0, 0, R};
Physical Volume("BALL") = {1};
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Mesh.MeshSizeFromCurvature = 0;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = 0;
