"""The simulated world and its sensors, where every sample sequence and laser scan comes from (the
modules are listed in ``docs/layout.md``). It uses the motion models and the file formats, never an
estimator: the wings build on it, not the other way round.
"""
