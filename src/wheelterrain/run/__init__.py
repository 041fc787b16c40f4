"""The run layer: one function per command that does the command's work (choose the engine
and the FMU folder, refuse what cannot be done before any work, run, write the files as one
set) between the layers that compute and the command line, which only parses, calls one of
these and prints (as FMPy's command line calls ``simulate_fmu``).

- :mod:`.rover`: ``wheelterrain rover`` (the registry of engines and controllers);
- :mod:`.rig`: ``wheelterrain reproduce`` (the paper's C1-C4 on the rig's FMU pair);
- :mod:`.calibrate`: ``wheelterrain calibrate`` (a fit, its held-out errors, the preset file).

Progress: each run takes ``progress(stage, done, total)``, told as each stage advances (the
limit's prediction, simulated seconds, cases); the command line draws it.
"""
