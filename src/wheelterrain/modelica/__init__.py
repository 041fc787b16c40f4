"""The WheelTerrain Modelica library, generated from the model's CasADi Functions and the one
parameter table (:mod:`.library`): the functions written out instruction by instruction
(:mod:`.translate`) and as CasADi's C (:mod:`.external`), the examples' reference results from
the Python model (:mod:`.reference`)."""
