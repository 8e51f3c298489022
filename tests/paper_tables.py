"""The paper's Table 2 (Patil, Lee & Hodges, AIAA 2001-0064), shared by the test files
(imported as a plain module: pytest puts tests/ on sys.path).  tests/ros_fakes.py keeps its
own copy: it is loaded by path in another process.

Eigenvalues in per-rev for N = 2, 3, 4 elements, as printed: the strings keep the printed
digits (a test's tolerance can depend on them), TABLE2 holds the same values as floats.
"""
from __future__ import annotations

#: (family, symmetry, index) -> printed per-rev for N = 2, 3, 4 elements
TABLE2_PRINTED = {
    ("flap", "symmetric", 1): ("2.43", "2.43", "2.4347"),
    ("flap", "antisymmetric", 1): ("8.28", "7.48", "7.3210"),
    ("flap", "symmetric", 2): ("24.08", "17.40", "15.5465"),
    ("flap", "antisymmetric", 2): ("58.67", "33.38", "28.3486"),
    ("torsion", "symmetric", 1): ("2.32", "2.30", "2.2896"),
    ("torsion", "antisymmetric", 1): ("2.33", "2.30", "2.2915"),
    ("torsion", "symmetric", 2): ("7.40", "6.84", "6.5738"),
    ("torsion", "antisymmetric", 2): ("7.40", "6.84", "6.5742"),
    ("lag", "symmetric", 1): ("4.81", "4.77", "4.7523"),
    ("lag", "antisymmetric", 1): ("5.06", "5.01", "4.9927"),
    ("lag", "symmetric", 2): ("52.07", "37.61", "33.5731"),
    ("lag", "antisymmetric", 2): ("51.94", "38.21", "34.1087"),
}
#: the same as floats
TABLE2 = {key: tuple(float(v) for v in row) for key, row in TABLE2_PRINTED.items()}
#: the teeter pair's real part, per-rev (N = 4): +-0.045299 +- 1i
TEETER_REAL_PER_REV = 0.045299
