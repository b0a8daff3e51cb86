#!/bin/sh
# Regenerates ball_reference.csv from scratch: gmsh meshes, CalculiX decks and
# runs, post-processing.  Needs gmsh (4.8), ccx (2.20), /usr/bin/python3 + numpy.
# Scratch files go to ./work (not committed).  Runs are single-threaded and
# sequential.  Extra arguments are passed on, e.g.
#   ./run.sh --only 'foam/coarse/*/*'      (material/mesh/case/theory globs)
#   ./run.sh --reuse                       (keep finished runs of unchanged decks)
set -eu
cd "$(dirname "$0")"
export OMP_NUM_THREADS=1
case " $* " in
  *" --reuse "*) ;;
  *) rm -rf work ;;
esac
mkdir -p work
/usr/bin/python3 reference.py "$@" 2>&1 | tee work/run.log
