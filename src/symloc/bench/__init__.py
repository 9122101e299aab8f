"""Evaluation: everything that knows the ground truth.

What runs on a robot (``localizer``, ``mcl``, ``slam``, ``symmetry``, ``vision``) never imports
this package. Here live the simulated episodes that drive the localizer's requests
(:mod:`~symloc.bench.episode`), the simulated mapping trip (:mod:`~symloc.bench.mapping_trip`),
the kidnapped-robot scenario (:mod:`~symloc.bench.scenario`), the paper's tables and the
demo, and the evaluation bench (world files, the world generator, whole-trial grading, sweeps).
"""
