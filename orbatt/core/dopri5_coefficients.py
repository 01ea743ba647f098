"""The Dormand-Prince 5(4) pair as data, in the layout of :mod:`orbatt.core.dop853_coefficients`:
the Butcher tableau, the 5th-order weights ``B`` and the error estimate ``E = B - BHAT`` (the
embedded solution of order 4).

Source: J. R. Dormand & P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
Appl. Math. 6 (1980) 19-26, the pair ``RK5(4)7M`` as in Hairer's ``dopri5.f`` (Hairer, Norsett &
Wanner, *Solving ODEs I*, 2nd ed., Sect. II.5, Table 5.2; scipy's ``RK45``). Every value below is
the float64 nearest to the published rational (``tests/methods/test_dopri5.py`` checks each
against it, and the order conditions up to order 5 of ``B`` and up to 4 of ``B - E``).

Seven stages, FSAL **inside the tableau**: row 7 of ``A`` is ``B`` (``b7 = 0``), so stage 7 is
``f(t + h, y_new)``, which the error estimate needs (``e7 = -1/40``) and the next step takes as
its first stage. The step loop (:func:`orbatt.core.rk_loop.loop_of`, :data:`LAST_STAGE_IS_NEW`)
evaluates it at the step's end time and reuses it: 6 evaluations per step attempt.

The table is the one source; a line is ``name  i [j]  value`` with 1-based stage numbers:
``c i`` (the nodes ``C``), ``a i j`` (the nonzero entries of ``A``), ``b i`` (the weights
``B``), ``e i`` (Hairer's ``e1 .. e7``: ``E = B - BHAT``). Entries not listed are zero. The
rationals: ``c = (0, 1/5, 3/10, 4/5, 8/9, 1, 1)``; ``a21 = 1/5``; ``a3 = (3/40, 9/40)``;
``a4 = (44/45, -56/15, 32/9)``; ``a5 = (19372/6561, -25360/2187, 64448/6561, -212/729)``;
``a6 = (9017/3168, -355/33, 46732/5247, 49/176, -5103/18656)``; ``a7 = b = (35/384, 0,
500/1113, 125/192, -2187/6784, 11/84, 0)``; ``e = (71/57600, 0, -71/16695, 71/1920,
-17253/339200, 22/525, -1/40)``.
"""
from __future__ import annotations

from .butcher import matrix, sparse_rows, vector

N_STAGES = 7
#: the order of the propagated solution (5) and of the embedded one (4)
ORDER = 5
ORDER_EMBEDDED = 4
#: the last stage is ``f(t + h, y_new)`` (row 7 of ``A`` is ``B``): the step loop evaluates it
#: at the step's end time and takes it as the next step's first stage
LAST_STAGE_IS_NEW = True

_TABLE = """
c    2        0.2
c    3        0.3
c    4        0.8
c    5        0.8888888888888888
c    6        1.0
c    7        1.0
a    2  1     0.2
a    3  1     0.075
a    3  2     0.225
a    4  1     0.9777777777777777
a    4  2     -3.7333333333333334
a    4  3     3.5555555555555554
a    5  1     2.9525986892242035
a    5  2     -11.595793324188385
a    5  3     9.822892851699436
a    5  4     -0.2908093278463649
a    6  1     2.8462752525252526
a    6  2     -10.757575757575758
a    6  3     8.906422717743473
a    6  4     0.2784090909090909
a    6  5     -0.2735313036020583
a    7  1     0.09114583333333333
a    7  3     0.44923629829290207
a    7  4     0.6510416666666666
a    7  5     -0.322376179245283
a    7  6     0.13095238095238096
b    1        0.09114583333333333
b    3        0.44923629829290207
b    4        0.6510416666666666
b    5        -0.322376179245283
b    6        0.13095238095238096
e    1        0.0012326388888888888
e    3        -0.0042527702905061394
e    4        0.03697916666666667
e    5        -0.05086379716981132
e    6        0.0419047619047619
e    7        -0.025
"""


#: nodes: stage ``s`` evaluates ``f`` at ``t + C[s] h``
C = vector(_TABLE, "c", N_STAGES)
#: the Butcher tableau (strictly lower triangular; its last row is ``B``)
A = matrix(_TABLE, "a", N_STAGES)
#: weights of the 5th-order solution ``y_new = y + h sum(B_i K_i)``
B = vector(_TABLE, "b", N_STAGES)
#: the error estimate ``y_new - y_hat = h sum(E_i K_i)`` (``y_hat`` of order 4)
E = vector(_TABLE, "e", N_STAGES)

# The nonzero entries of A, row by row (as in dop853_coefficients)
A_PTR, A_COL, A_VAL = sparse_rows(A)
