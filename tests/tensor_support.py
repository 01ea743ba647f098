"""What the tensor tests share: the shipped wheel slew with a full inertia tensor, and the
sensors (gyro, star tracker, MEKF) they add to it."""
from __future__ import annotations

import re

from orbatt.shipped import shipped_file

#: the wheel slew's principal moments as a tensor with products of inertia 3, -2, 1 g m^2
SIX = 'inertia = ["0.13 kg m2", "0.11 kg m2", "0.05 kg m2", "0.003 kg m2", "-0.002 kg m2", "0.001 kg m2"]'
SENSORS = '''
[sensors]
seed = 7

[sensors.gyro]
rate = "10 Hz"
arw = "0.15 deg/sqrt(h)"
bias = ["5 deg/h", "-3 deg/h", "2 deg/h"]

[sensors.star_tracker]
rate = "1 Hz"
noise = "10 arcsec"

[estimator]
kind = "mekf"
attitude_sigma = "0.1 deg"
bias_sigma = "10 deg/h"
'''


def tensor_slew_text(t_end="20 s", sensors=False):
    """The shipped wheel slew (three wheels, a PD law with max_torque and max_rate, a 10 Hz
    flight software, the gravity gradient) with a full tensor, shortened."""
    text = shipped_file("cubesat-slew-wheels").read_text()
    text = text.replace('inertia = ["0.13 kg m2", "0.11 kg m2", "0.05 kg m2"]', SIX, 1)
    if sensors:
        text = text.replace('period = "0.1 s"\n', 'period = "0.1 s"\n' + SENSORS, 1)
    return re.sub(r't_end = "[^"]*"', f't_end = "{t_end}"', text)
