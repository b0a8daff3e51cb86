#!/usr/bin/env bash
# Regenerates the shipped tetrahedral meshes of the unit ball (ball_L1..4.msh, gmsh MSH 2.2
# ASCII) from ball.geo with Debian's gmsh (apt-get install gmsh). Run offline; the programs read
# the .msh files and never need gmsh for the ball. Level: size at the poles / size elsewhere, in
# units of the radius.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
mesh() {  # level htop hmax
  gmsh -3 ball.geo -setnumber htop "$2" -setnumber hmax "$3" \
    -format msh22 -o "ball_L$1.msh" -v 1
}
mesh 1 0.05 0.35
mesh 2 0.035 0.28
mesh 3 0.025 0.22
mesh 4 0.016 0.16
