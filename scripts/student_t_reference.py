#!/usr/bin/env python3
"""scipy.stats.t.ppf reference values for tests/student_t.rs: a grid over
SPEC §5's range (n in [3, 1000] -> nu = n - 1, alpha in [1e-6, 0.2]) plus
random off-grid pairs. Usage: python3 scripts/student_t_reference.py"""
import os
import numpy as np
from scipy import stats

out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "student_t_ppf.csv")
rows = []
for n in [3, 4, 5, 6, 8, 10, 12, 15, 20, 30, 50, 100, 200, 500, 1000]:
    for a in [1e-6, 1e-5, 1e-4, 1e-3, 0.01, 0.025, 0.05, 0.1, 0.2]:
        rows.append((n - 1, a, stats.t.ppf(1 - a, n - 1) if a > 1e-4 else stats.t.isf(a, n - 1)))
rng = np.random.default_rng(7)
for _ in range(60):
    n = int(rng.integers(3, 1001))
    a = float(10 ** rng.uniform(-6, np.log10(0.2)))
    rows.append((n - 1, a, stats.t.isf(a, n - 1)))
with open(out, "w") as fh:
    fh.write("nu,alpha,t\n")
    for nu, a, t in rows:
        fh.write(f"{nu},{a!r},{float(t)!r}\n")
print("wrote", out, len(rows), "rows")
