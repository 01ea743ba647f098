"""Verner's 9(8) "most efficient" Runge-Kutta pair as data, in the layout of
:mod:`orbatt.core.dop853_coefficients`: the Butcher tableau, the 9th-order weights ``B``, the
embedded 8th-order weights ``BHAT`` and the error estimate ``E = B - BHAT``.

Source: J. H. Verner, "Numerically optimal Runge-Kutta pairs with interpolants", Numer.
Algorithms 53 (2010) 383-396, the 16-stage pair of order 9(8) (``c2 = 0.03462``; the pair
OrdinaryDiffEq.jl calls ``Vern9``). The numbers below are the Float64 values transcribed from
the ``Vern9Tableau`` of OrdinaryDiffEq.jl (``lib/OrdinaryDiffEqVerner/src/verner_tableaus.jl``,
its ``CompiledFloats`` variant, itself from Verner's published rational/radical coefficients);
``tests/core/test_verner98.py`` checks them independently (row sums, the quadrature order
conditions, the convergence orders 9 and 8 of the two solutions).

Stage ``s`` uses ``K[0..s-1]``; stages 15 and 16 are both evaluated at ``t + h``: stage 15
enters the 9th-order solution, stage 16 only the 8th-order one. There is no FSAL: the first
stage of the next step is ``f(t + h, y_new)``, which the step loop evaluates on acceptance
(16 evaluations per accepted step, 15 per rejected one).

The table is the one source; a line is ``name  i [j]  value`` with Verner's 1-based stage
numbers: ``c i`` (the nodes ``C``), ``a i j`` (the nonzero entries of ``A``), ``b i`` (the
9th-order weights ``B``), ``bhat i`` (the 8th-order weights ``BHAT``). Entries not listed are
zero; ``C`` of stages 15 and 16 is 1.
"""
from __future__ import annotations

from .butcher import matrix, sparse_rows, vector

N_STAGES = 16
#: the order of the propagated solution (9) and of the embedded one (8)
ORDER = 9
ORDER_EMBEDDED = 8

_TABLE = """
c       1      0.0
c       2      0.03462
c       3      0.09702435063878045
c       4      0.14553652595817068
c       5      0.561
c       6      0.22900791159048503
c       7      0.544992088409515
c       8      0.645
c       9      0.48375
c      10      0.06757
c      11      0.25
c      12      0.6590650618730999
c      13      0.8206
c      14      0.9012
a       2   1  0.03462
a       3   1  -0.03893354388572875
a       3   2  0.13595789452450918
a       4   1  0.03638413148954267
a       4   3  0.10915239446862801
a       5   1  2.0257639143939694
a       5   3  -7.638023836496291
a       5   4  6.173259922102322
a       6   1  0.05112275589406061
a       6   4  0.17708237945550218
a       6   5  0.0008027762409222536
a       7   1  0.13160063579752163
a       7   4  -0.2957276252669636
a       7   5  0.08781378035642955
a       7   6  0.6213052975225274
a       8   1  0.07166666666666667
a       8   6  0.33055335789153195
a       8   7  0.2427799754418014
a       9   1  0.071806640625
a       9   6  0.3294380283228177
a       9   7  0.1165190029271823
a       9   8  -0.034013671875
a      10   1  0.04836757646340646
a      10   6  0.03928989925676164
a      10   7  0.10547409458903446
a      10   8  -0.021438652846483126
a      10   9  -0.10412291746271944
a      11   1  -0.026645614872014785
a      11   6  0.03333333333333333
a      11   7  -0.1631072244872467
a      11   8  0.03396081684127761
a      11   9  0.1572319413814626
a      11  10  0.21522674780318796
a      12   1  0.03689009248708622
a      12   6  -0.1465181576725543
a      12   7  0.2242577768172024
a      12   8  0.02294405717066073
a      12   9  -0.0035850052905728597
a      12  10  0.08669223316444385
a      12  11  0.43838406519683376
a      13   1  -0.4866012215113341
a      13   6  -6.304602650282853
a      13   7  -0.2812456182894729
a      13   8  -2.679019236219849
a      13   9  0.5188156639241577
a      13  10  1.3653531876033418
a      13  11  5.8850910885039465
a      13  12  2.8028087862720628
a      14   1  0.4185367457753472
a      14   6  6.724547581906459
a      14   7  -0.42544428016461133
a      14   8  3.3432791530012653
a      14   9  0.6170816631175374
a      14  10  -0.9299661239399329
a      14  11  -6.099948804751011
a      14  12  -3.002206187889399
a      14  13  0.2553202529443446
a      15   1  -0.7793740861228848
a      15   6  -13.937342538107776
a      15   7  1.2520488533793563
a      15   8  -14.691500408016868
a      15   9  -0.494705058533141
a      15  10  2.2429749091462368
a      15  11  13.367893803828643
a      15  12  14.396650486650687
a      15  13  -0.79758133317768
a      15  14  0.4409353709534278
a      16   1  2.0580513374668867
a      16   6  22.357937727968032
a      16   7  0.9094981099755646
a      16   8  35.89110098240264
a      16   9  -3.442515027624454
a      16  10  -4.865481358036369
a      16  11  -18.909803813543427
a      16  12  -34.26354448030452
a      16  13  1.2647565216956427
b       1      0.014611976858423152
b       8      -0.3915211862331339
b       9      0.23109325002895065
b      10      0.12747667699928525
b      11      0.2246434176204158
b      12      0.5684352689748513
b      13      0.058258715572158275
b      14      0.13643174034822156
b      15      0.030570139830827976
bhat    1      0.01996996514886773
bhat    8      2.19149930494933
bhat    9      0.08857071848208438
bhat   10      0.11405602348659656
bhat   11      0.2533163805345107
bhat   12      -2.056564386240941
bhat   13      0.340809679901312
bhat   16      0.04834231373823958
c      15      1.0
c      16      1.0
"""


#: nodes: stage ``s`` evaluates ``f`` at ``t + C[s] h``
C = vector(_TABLE, "c", N_STAGES)
#: the Butcher tableau (strictly lower triangular)
A = matrix(_TABLE, "a", N_STAGES)
#: weights of the 9th-order solution ``y_new = y + h sum(B_i K_i)``
B = vector(_TABLE, "b", N_STAGES)
#: weights of the embedded 8th-order solution
BHAT = vector(_TABLE, "bhat", N_STAGES)
#: the error estimate ``y_new - y_hat = h sum(E_i K_i)``
E = B - BHAT

# The nonzero entries of A, row by row (as in dop853_coefficients)
A_PTR, A_COL, A_VAL = sparse_rows(A)
