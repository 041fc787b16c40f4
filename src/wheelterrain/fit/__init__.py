"""Fitting and judging the model against rig data: calibration (:mod:`.calibration`),
sensitivity (:mod:`.sensitivity`) and the prediction protocols of ``wheelterrain validate``
(:mod:`.prediction`)."""
