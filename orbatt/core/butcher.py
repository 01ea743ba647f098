"""Runge-Kutta pairs written as text tables (the coefficient modules
:mod:`orbatt.core.dop853_coefficients` and :mod:`orbatt.core.verner98_coefficients`): reading
their lines and the sparse rows of the tableau the compiled step loop runs.

A table line is ``name  i [j]  value`` with 1-based stage numbers (the papers' numbering);
entries not listed are zero.
"""
from __future__ import annotations

import numpy as np

__all__ = ["entries", "vector", "matrix", "sparse_rows"]


def entries(table, name):
    """``[(indices (0-based), value)]`` of the lines of ``table`` (text) named ``name``, in
    table order."""
    out = []
    for line in table.splitlines():
        fields = line.split()
        if fields and fields[0] == name:
            out.append((tuple(int(i) - 1 for i in fields[1:-1]), float(fields[-1])))
    return out


def vector(table, name, n):
    """The ``(n,)`` vector of the lines ``name  i  value``."""
    v = np.zeros(n)
    for (i,), value in entries(table, name):
        v[i] = value
    return v


def matrix(table, name, n):
    """The ``(n, n)`` matrix of the lines ``name  i  j  value`` (the Butcher tableau ``A``)."""
    a = np.zeros((n, n))
    for (i, j), value in entries(table, name):
        a[i, j] = value
    return a


def sparse_rows(a):
    """``(A_PTR, A_COL, A_VAL)``: the nonzero entries of the strictly lower triangular ``a``, row
    by row (stage ``s`` combines ``A_VAL[A_PTR[s]:A_PTR[s+1]]`` with the stages
    ``A_COL[A_PTR[s]:A_PTR[s+1]]``): the step loop skips the tableau's zeros."""
    n = a.shape[0]
    ptr = np.zeros(n + 1, dtype=np.int64)
    col = np.array([j for s in range(n) for j in range(s) if a[s, j] != 0.0], dtype=np.int64)
    val = np.array([a[s, j] for s in range(n) for j in range(s) if a[s, j] != 0.0])
    for s in range(n):
        ptr[s + 1] = ptr[s] + np.count_nonzero(a[s, :s])
    return ptr, col, val
