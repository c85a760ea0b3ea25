"""[Zhao]'s printed timings, stored once: the command line, the benchmarks and the notebooks read
them from here."""

from __future__ import annotations

#: [Zhao], Table 1: mean milliseconds of stereo processing, parameter estimation and Kalman
#: filtering at each of the five resolutions the paper timed, by (width, height).
PAPER_TABLE1 = {
    (640, 480): {"stereo": 48.969, "estimation": 0.874, "kalman": 0.161},
    (512, 384): {"stereo": 39.851, "estimation": 0.664, "kalman": 0.157},
    (400, 300): {"stereo": 31.970, "estimation": 0.754, "kalman": 0.158},
    (320, 240): {"stereo": 22.165, "estimation": 0.662, "kalman": 0.168},
    (256, 192): {"stereo": 22.460, "estimation": 0.610, "kalman": 0.153},
}
#: [Zhao], IV.A.1: the long run's frames, and the mean and standard deviation of the whole frame
#: over them (ms; resolution not stated).
PAPER_LONG_RUN = (10_000, 26.5511, 4.551)
