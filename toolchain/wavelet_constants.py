"""The Daubechies scaling filters of csrc/src/denoise.c to 25 digits.

The C library holds the filters as decimal literals. They come from here:
Newton's method in 50-digit decimal arithmetic on the equations that
define the extremal-phase Daubechies filter with p vanishing moments and
2p taps h[0..2p−1] (Daubechies 1992, ch. 6),

    Σ_k h[k] h[k + 2m] = δ_m          m = 0 … p−1   (orthonormal shifts)
    Σ_k (−1)^k k^j h[k] = 0           j = 0 … p−1   (p vanishing moments)

started from the float64 spectral factorization of
:func:`attitude_c.denoise.reference.daubechies` (which picks the extremal
phase). ``python -m toolchain.wavelet_constants`` prints the C table;
tests/test_denoise.py checks that the C literals are these values
rounded to double.
"""

from __future__ import annotations

import sys
from decimal import Decimal, getcontext

getcontext().prec = 50

#: vanishing moments of each C table
TABLES = {"haar": 1, "db2": 2, "db4": 4}


def _equations(h: list[Decimal], p: int) -> tuple[list[Decimal], list[list[Decimal]]]:
    n = len(h)
    f: list[Decimal] = []
    jac: list[list[Decimal]] = []
    for m in range(p):
        f.append(sum((h[k] * h[k + 2 * m] for k in range(n - 2 * m)), Decimal(0)) - (1 if m == 0 else 0))
        row = [Decimal(0)] * n
        for k in range(n - 2 * m):
            row[k] += h[k + 2 * m]
            row[k + 2 * m] += h[k]
        jac.append(row)
    for j in range(p):
        coef = [Decimal((-1) ** k) * Decimal(k) ** j if (k or j) else Decimal(1) for k in range(n)]
        f.append(sum((c * x for c, x in zip(coef, h)), Decimal(0)))
        jac.append(coef)
    return f, jac


def _solve(a: list[list[Decimal]], b: list[Decimal]) -> list[Decimal]:
    n = len(b)
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for c in range(n):
        piv = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[piv] = m[piv], m[c]
        for r in range(n):
            if r != c:
                k = m[r][c] / m[c][c]
                m[r] = [x - k * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]


def daubechies_decimal(p: int) -> list[Decimal]:
    """h[0..2p−1] of the extremal-phase filter, 50 digits, Σh = √2."""
    from attitude_c.denoise.reference import daubechies

    h = [Decimal(repr(float(v))) for v in daubechies(p)]
    for _ in range(8):  # quadratic convergence: 16 → 32 → 64 digits
        f, jac = _equations(h, p)
        step = _solve(jac, [-v for v in f])
        h = [x + s for x, s in zip(h, step)]
    return h


def c_table() -> str:
    lines = []
    for name, p in TABLES.items():
        h = daubechies_decimal(p)
        vals = ", ".join(f"ATT_R({v:.25e})" for v in h)
        lines.append(f"static const att_real {name}_h[{len(h)}] = {{ {vals} }};")
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover
    sys.stdout.write(c_table() + "\n")
