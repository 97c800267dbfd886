"""Small dense linear algebra in plain floats: 3-vectors and 3x3 matrices (row by row), and for
the filters' covariances a symmetric matrix kept as its lower triangle row by row ("packed"),
Cholesky factors written out for the sizes the filters use, and a Jacobi eigen-decomposition
for a covariance that rounding made indefinite. Plain Python floats and written-out operations,
so that the C twins (fusion_core/native) do the same operations in the same order and agree bit
for bit."""

from __future__ import annotations

import math
from typing import Final

Vec3 = tuple[float, float, float]
Mat9 = tuple[float, float, float, float, float, float, float, float, float]


def vec_sub(a: Vec3, b: Vec3) -> Vec3:
    """a - b."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mat_vec(m: Mat9, v: Vec3) -> Vec3:
    """m v for a 3x3 matrix m given row by row."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)


def mat_t_vec(m: Mat9, v: Vec3) -> Vec3:
    """m^T v for a 3x3 matrix m given row by row."""
    x, y, z = v
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)


def packed_size(t: tuple[float, ...]) -> int:
    """The order n of the square matrix whose packed lower triangle is t (n (n + 1) / 2
    values)."""
    n = int((math.isqrt(8 * len(t) + 1) - 1) // 2)
    if n * (n + 1) // 2 != len(t):
        raise ValueError(f"{len(t)} values are no packed lower triangle")
    return n


def unpacked(t: tuple[float, ...]) -> list[list[float]]:
    """The packed lower triangle t as a full square list of lists."""
    n = packed_size(t)
    return [[t[packed_index(i, j)] for j in range(n)] for i in range(n)]


def packed(value: list[list[float]]) -> tuple[float, ...]:
    """The lower triangle of a square matrix, row by row."""
    return tuple(float(value[i][j]) for i in range(len(value)) for j in range(i + 1))


def packed_index(i: int, j: int) -> int:
    """Position of P[i][j] in the row-by-row lower triangle."""
    if j > i:
        i, j = j, i
    return i * (i + 1) // 2 + j


def packed_diagonal(d: tuple[float, ...]) -> tuple[float, ...]:
    """The packed lower triangle of diag(d)."""
    return tuple(d[i] if i == j else 0.0 for i in range(len(d)) for j in range(i + 1))


def sigma_offsets(P: tuple[float, ...], gamma: float) -> list[tuple[float, ...]]:
    """The columns of gamma L, L the lower Cholesky factor of the packed 6x6 P (P = L L^T);
    Cholesky-Banachiewicz, row by row, written out. For a P that rounding made indefinite,
    those of psd_sqrt_columns."""
    (p00, p10, p11, p20, p21, p22, p30, p31, p32, p33,
     p40, p41, p42, p43, p44, p50, p51, p52, p53, p54, p55) = P
    if not p00 > 0.0:
        return psd_sqrt_columns(P, gamma)
    l00 = math.sqrt(p00)
    i0 = 1.0 / l00
    l10 = p10 * i0
    d = p11 - l10 * l10
    if not d > 0.0:
        return psd_sqrt_columns(P, gamma)
    l11 = math.sqrt(d)
    i1 = 1.0 / l11
    l20 = p20 * i0
    l21 = (p21 - l20 * l10) * i1
    d = p22 - l20 * l20 - l21 * l21
    if not d > 0.0:
        return psd_sqrt_columns(P, gamma)
    l22 = math.sqrt(d)
    i2 = 1.0 / l22
    l30 = p30 * i0
    l31 = (p31 - l30 * l10) * i1
    l32 = (p32 - l30 * l20 - l31 * l21) * i2
    d = p33 - l30 * l30 - l31 * l31 - l32 * l32
    if not d > 0.0:
        return psd_sqrt_columns(P, gamma)
    l33 = math.sqrt(d)
    i3 = 1.0 / l33
    l40 = p40 * i0
    l41 = (p41 - l40 * l10) * i1
    l42 = (p42 - l40 * l20 - l41 * l21) * i2
    l43 = (p43 - l40 * l30 - l41 * l31 - l42 * l32) * i3
    d = p44 - l40 * l40 - l41 * l41 - l42 * l42 - l43 * l43
    if not d > 0.0:
        return psd_sqrt_columns(P, gamma)
    l44 = math.sqrt(d)
    l50 = p50 * i0
    l51 = (p51 - l50 * l10) * i1
    l52 = (p52 - l50 * l20 - l51 * l21) * i2
    l53 = (p53 - l50 * l30 - l51 * l31 - l52 * l32) * i3
    l54 = (p54 - l50 * l40 - l51 * l41 - l52 * l42 - l53 * l43) / l44
    d = p55 - l50 * l50 - l51 * l51 - l52 * l52 - l53 * l53 - l54 * l54
    if not d > 0.0:
        return psd_sqrt_columns(P, gamma)
    g = gamma
    return [
        (g * l00, g * l10, g * l20, g * l30, g * l40, g * l50),
        (0.0, g * l11, g * l21, g * l31, g * l41, g * l51),
        (0.0, 0.0, g * l22, g * l32, g * l42, g * l52),
        (0.0, 0.0, 0.0, g * l33, g * l43, g * l53),
        (0.0, 0.0, 0.0, 0.0, g * l44, g * l54),
        (0.0, 0.0, 0.0, 0.0, 0.0, g * math.sqrt(d)),
    ]


JACOBI_SWEEPS: Final = 30
"""Most sweeps of the Jacobi eigenvalue iteration (a 6x6 matrix converges in well under 10)."""


def psd_sqrt_columns(P: tuple[float, ...], gamma: float) -> list[tuple[float, ...]]:
    """For a P that rounding made indefinite: the columns of gamma V sqrt(max(w, 0)), P = V
    diag(w) V^T by cyclic Jacobi rotations (Golub & Van Loan, Matrix Computations, 8.5) in
    plain floats, so that the C twin does the same operations (never raises for a finite P)."""
    n = packed_size(P)
    A = [[P[packed_index(i, j)] for j in range(n)] for i in range(n)]
    V = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for _ in range(JACOBI_SWEEPS):
        off = 0.0
        for i in range(n):
            for j in range(i + 1, n):
                off += A[i][j] * A[i][j]
        if off == 0.0:
            break
        for p in range(n):
            for q in range(p + 1, n):
                apq = A[p][q]
                if apq == 0.0:
                    continue
                theta = (A[q][q] - A[p][p]) / (2.0 * apq)
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):  # A <- A J (columns p and q)
                    akp, akq = A[k][p], A[k][q]
                    A[k][p] = c * akp - s * akq
                    A[k][q] = s * akp + c * akq
                for k in range(n):  # A <- J^T A (rows p and q)
                    apk, aqk = A[p][k], A[q][k]
                    A[p][k] = c * apk - s * aqk
                    A[q][k] = s * apk + c * aqk
                for k in range(n):  # V <- V J
                    vkp, vkq = V[k][p], V[k][q]
                    V[k][p] = c * vkp - s * vkq
                    V[k][q] = s * vkp + c * vkq
    out = []
    for j in range(n):
        root = gamma * math.sqrt(A[j][j]) if A[j][j] > 0.0 else 0.0
        out.append(tuple(V[k][j] * root for k in range(n)))
    return out


def cholesky3(
    s00: float, s10: float, s11: float, s20: float, s21: float, s22: float,
) -> tuple[float, float, float, float, float, float] | None:
    """The packed lower Cholesky factor of a packed 3x3 S, or None when S is not positive
    definite."""
    if not s00 > 0.0:
        return None
    l00 = math.sqrt(s00)
    l10 = s10 / l00
    d = s11 - l10 * l10
    if not d > 0.0:
        return None
    l11 = math.sqrt(d)
    l20 = s20 / l00
    l21 = (s21 - l20 * l10) / l11
    d = s22 - l20 * l20 - l21 * l21
    if not d > 0.0:
        return None
    return l00, l10, l11, l20, l21, math.sqrt(d)


def cholesky4(
    s00: float, s10: float, s11: float, s20: float, s21: float, s22: float,
    s30: float, s31: float, s32: float, s33: float,
) -> tuple[float, ...] | None:
    """The packed lower Cholesky factor of a packed 4x4 S, or None when S is not positive
    definite: cholesky3 of its leading 3x3 block, then the last row."""
    L3 = cholesky3(s00, s10, s11, s20, s21, s22)
    if L3 is None:
        return None
    l00, l10, l11, l20, l21, l22 = L3
    l30 = s30 / l00
    l31 = (s31 - l30 * l10) / l11
    l32 = (s32 - l30 * l20 - l31 * l21) / l22
    d = s33 - l30 * l30 - l31 * l31 - l32 * l32
    if not d > 0.0:
        return None
    return l00, l10, l11, l20, l21, l22, l30, l31, l32, math.sqrt(d)
