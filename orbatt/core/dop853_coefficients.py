"""The Dormand-Prince 8(5,3) pair as data: the Butcher tableau, the 8th-order weights and the
5th- and 3rd-order error estimates, from Hairer's ``dop853.f`` (30 digits, as in scipy's
``dop853_coefficients.py``). Stage ``s`` uses ``K[0..s-1]``; ``K[12]`` is ``f(t + h, y_new)``
(FSAL). The step loops of :mod:`orbatt.core.dop853` read the nonzero entries of ``A`` row
by row through ``A_PTR``, ``A_COL``, ``A_VAL``.

The table below is the one source; a line is ``name  i [j]  value`` with Hairer's names and
his 1-based stage numbers: ``c i`` (the nodes ``C``), ``a i j`` (the nonzero entries of the
tableau ``A``), ``b i`` (the weights ``B``), ``bhh i`` (Hairer's ``bhh1, bhh2, bhh3``, which
act on stages 1, 9 and 12: ``E3 = B - bhh``) and ``er i`` (the 5th-order estimate ``E5``).
Entries not listed are zero.
"""
from __future__ import annotations

import numpy as np

N_STAGES = 12
ORDER = 8

_TABLE = """
c     1        0.0
c     2        0.526001519587677318785587544488e-01
c     3        0.789002279381515978178381316732e-01
c     4        0.118350341907227396726757197510
c     5        0.281649658092772603273242802490
c     6        0.333333333333333333333333333333
c     7        0.25
c     8        0.307692307692307692307692307692
c     9        0.651282051282051282051282051282
c    10        0.6
c    11        0.857142857142857142857142857142
c    12        1.0
a     2   1    5.26001519587677318785587544488e-2
a     3   1    1.97250569845378994544595329183e-2
a     3   2    5.91751709536136983633785987549e-2
a     4   1    2.95875854768068491816892993775e-2
a     4   3    8.87627564304205475450678981324e-2
a     5   1    2.41365134159266685502369798665e-1
a     5   3   -8.84549479328286085344864962717e-1
a     5   4    9.24834003261792003115737966543e-1
a     6   1    3.7037037037037037037037037037e-2
a     6   4    1.70828608729473871279604482173e-1
a     6   5    1.25467687566822425016691814123e-1
a     7   1    3.7109375e-2
a     7   4    1.70252211019544039314978060272e-1
a     7   5    6.02165389804559606850219397283e-2
a     7   6   -1.7578125e-2
a     8   1    3.70920001185047927108779319836e-2
a     8   4    1.70383925712239993810214054705e-1
a     8   5    1.07262030446373284651809199168e-1
a     8   6   -1.53194377486244017527936158236e-2
a     8   7    8.27378916381402288758473766002e-3
a     9   1    6.24110958716075717114429577812e-1
a     9   4   -3.36089262944694129406857109825
a     9   5   -8.68219346841726006818189891453e-1
a     9   6    2.75920996994467083049415600797e1
a     9   7    2.01540675504778934086186788979e1
a     9   8   -4.34898841810699588477366255144e1
a    10   1    4.77662536438264365890433908527e-1
a    10   4   -2.48811461997166764192642586468
a    10   5   -5.90290826836842996371446475743e-1
a    10   6    2.12300514481811942347288949897e1
a    10   7    1.52792336328824235832596922938e1
a    10   8   -3.32882109689848629194453265587e1
a    10   9   -2.03312017085086261358222928593e-2
a    11   1   -9.3714243008598732571704021658e-1
a    11   4    5.18637242884406370830023853209
a    11   5    1.09143734899672957818500254654
a    11   6   -8.14978701074692612513997267357
a    11   7   -1.85200656599969598641566180701e1
a    11   8    2.27394870993505042818970056734e1
a    11   9    2.49360555267965238987089396762
a    11  10   -3.0467644718982195003823669022
a    12   1    2.27331014751653820792359768449
a    12   4   -1.05344954667372501984066689879e1
a    12   5   -2.00087205822486249909675718444
a    12   6   -1.79589318631187989172765950534e1
a    12   7    2.79488845294199600508499808837e1
a    12   8   -2.85899827713502369474065508674
a    12   9   -8.87285693353062954433549289258
a    12  10    1.23605671757943030647266201528e1
a    12  11    6.43392746015763530355970484046e-1
b     1        5.42937341165687622380535766363e-2
b     6        4.45031289275240888144113950566
b     7        1.89151789931450038304281599044
b     8       -5.8012039600105847814672114227
b     9        3.1116436695781989440891606237e-1
b    10       -1.52160949662516078556178806805e-1
b    11        2.01365400804030348374776537501e-1
b    12        4.47106157277725905176885569043e-2
bhh   1        0.244094488188976377952755905512
bhh   9        0.733846688281611857341361741547
bhh  12        0.220588235294117647058823529412e-1
er    1        0.1312004499419488073250102996e-1
er    6       -0.1225156446376204440720569753e+1
er    7       -0.4957589496572501915214079952
er    8        0.1664377182454986536961530415e+1
er    9       -0.3503288487499736816886487290
er   10        0.3341791187130174790297318841
er   11        0.8192320648511571246570742613e-1
er   12       -0.2235530786388629525884427845e-1
"""


def _entries(name):
    """``[(indices (0-based), value)]`` of the table's lines named ``name``, in table order."""
    out = []
    for line in _TABLE.splitlines():
        fields = line.split()
        if fields and fields[0] == name:
            out.append((tuple(int(i) - 1 for i in fields[1:-1]), float(fields[-1])))
    return out


def _vector(name):
    v = np.zeros(N_STAGES)
    for (i,), value in _entries(name):
        v[i] = value
    return v


#: nodes: stage ``s`` evaluates ``f`` at ``t + C[s] h``
C = _vector("c")
#: the Butcher tableau (strictly lower triangular)
A = np.zeros((N_STAGES, N_STAGES))
for (_i, _j), _value in _entries("a"):
    A[_i, _j] = _value
#: weights of the 8th-order solution ``y_new = y + h sum(B_i K_i)``
B = _vector("b")
#: 3rd-order error estimate ``B - bhh``
E3 = B - _vector("bhh")
#: 5th-order error estimate (Hairer's ``er1, er6..er12``)
E5 = _vector("er")

# The nonzero entries of A, row by row (stage s uses A_VAL[A_PTR[s]:A_PTR[s+1]] on the
# stages A_COL[...]): the stage loop skips the zeros of the tableau.
A_PTR = np.zeros(N_STAGES + 1, dtype=np.int64)
A_COL = np.array([j for s in range(N_STAGES) for j in range(s) if A[s, j] != 0.0], dtype=np.int64)
A_VAL = np.array([A[s, j] for s in range(N_STAGES) for j in range(s) if A[s, j] != 0.0])
for _s in range(N_STAGES):
    A_PTR[_s + 1] = A_PTR[_s] + np.count_nonzero(A[_s, :_s])
del _s, _i, _j, _value
