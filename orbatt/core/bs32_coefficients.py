"""The Bogacki-Shampine 3(2) pair as data, in the layout of :mod:`orbatt.core.dop853_coefficients`:
the Butcher tableau, the 3rd-order weights ``B`` and the error estimate ``E = B - BHAT`` (the
embedded solution of order 2).

Source: P. Bogacki & L. F. Shampine, "A 3(2) pair of Runge-Kutta formulas", Appl. Math. Lett. 2
(1989) 321-325 (MATLAB's ``ode23``, scipy's ``RK23``). Every value below is the float64 nearest to
the published rational (``tests/methods/test_bs32.py`` checks each against it, and the order
conditions up to order 3 of ``B`` and up to 2 of ``B - E``).

Four stages, FSAL **inside the tableau** (as Dormand-Prince 5(4),
:mod:`orbatt.core.dopri5_coefficients`): row 4 of ``A`` is ``B`` (``b4 = 0``), so stage 4 is
``f(t + h, y_new)``, which the error estimate needs (``e4 = -1/8``) and the next step takes as its
first stage: 3 evaluations per step attempt in the step loop (:data:`LAST_STAGE_IS_NEW`).

The table is the one source; a line is ``name  i [j]  value`` with 1-based stage numbers:
``c i`` (the nodes ``C``), ``a i j`` (the nonzero entries of ``A``), ``b i`` (the weights
``B``), ``e i`` (``E = B - BHAT``). Entries not listed are zero. The rationals: ``c = (0, 1/2,
3/4, 1)``; ``a21 = 1/2``; ``a3 = (0, 3/4)``; ``a4 = b = (2/9, 1/3, 4/9, 0)``; ``bhat = (7/24,
1/4, 1/3, 1/8)``, so ``e = (-5/72, 1/12, 1/9, -1/8)``.
"""
from __future__ import annotations

from .butcher import matrix, sparse_rows, vector

N_STAGES = 4
#: the order of the propagated solution (3) and of the embedded one (2)
ORDER = 3
ORDER_EMBEDDED = 2
#: the last stage is ``f(t + h, y_new)`` (row 4 of ``A`` is ``B``): the step loop evaluates it
#: at the step's end time and takes it as the next step's first stage
LAST_STAGE_IS_NEW = True

_TABLE = """
c    2        0.5
c    3        0.75
c    4        1.0
a    2  1     0.5
a    3  2     0.75
a    4  1     0.2222222222222222
a    4  2     0.3333333333333333
a    4  3     0.4444444444444444
b    1        0.2222222222222222
b    2        0.3333333333333333
b    3        0.4444444444444444
e    1        -0.06944444444444445
e    2        0.08333333333333333
e    3        0.1111111111111111
e    4        -0.125
"""


#: nodes: stage ``s`` evaluates ``f`` at ``t + C[s] h``
C = vector(_TABLE, "c", N_STAGES)
#: the Butcher tableau (strictly lower triangular; its last row is ``B``)
A = matrix(_TABLE, "a", N_STAGES)
#: weights of the 3rd-order solution ``y_new = y + h sum(B_i K_i)``
B = vector(_TABLE, "b", N_STAGES)
#: the error estimate ``y_new - y_hat = h sum(E_i K_i)`` (``y_hat`` of order 2)
E = vector(_TABLE, "e", N_STAGES)

# The nonzero entries of A, row by row (as in dop853_coefficients)
A_PTR, A_COL, A_VAL = sparse_rows(A)
