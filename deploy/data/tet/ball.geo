// The unit ball of the volumetric FEM (scaled to the scene's radius at load). Elements of size
// htop within 0.08 of the top pole (where the tip presses), 2 htop within 0.35 of the bottom
// pole (where the floor carries the ball: a wider, flatter contact), growing to hmax elsewhere.
// htop and hmax come from make_ball_meshes.sh (-setnumber).
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1.0};
Point(100) = {0, 0, 1.0};
Point(101) = {0, 0, -1.0};
Field[1] = Distance;
Field[1].PointsList = {100};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = htop;
Field[2].SizeMax = hmax;
Field[2].DistMin = 0.08;
Field[2].DistMax = 0.6;
Field[3] = Distance;
Field[3].PointsList = {101};
Field[4] = Threshold;
Field[4].InField = 3;
Field[4].SizeMin = 2 * htop;
Field[4].SizeMax = hmax;
Field[4].DistMin = 0.35;
Field[4].DistMax = 0.8;
Field[5] = Min;
Field[5].FieldsList = {2, 4};
Background Field = 5;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = 1;
Mesh.Optimize = 1;
Mesh.RandomSeed = 1;
