"""Speed measurements (``make bench``): ratios against a baseline measured in the same run.

Every bench runs numpy's BLAS on one thread unless the caller says otherwise: two spinning BLAS threads per process
inflated the CPU seconds the benches report (a locate read 20-54 CPU-s where one thread takes 5) and, with several
benches at once on two cores, their wall time several fold. Set here, before any bench module imports numpy
(``python -m bench.<name>`` imports this package first)."""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
