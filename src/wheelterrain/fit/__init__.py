"""Fitting and judging the model against rig data: calibration (:mod:`.calibration`),
sensitivity (:mod:`.sensitivity`), the test-data format (:mod:`.datasets`), model forms across
wheels and soils with prediction intervals (:mod:`.crosswheel`) and the prediction protocols of
``wheelterrain validate`` (:mod:`.prediction`)."""
