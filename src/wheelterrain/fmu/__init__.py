"""The FMUs: the per-step Functions both flavours call (:mod:`.functions`), what runs inside
the pythonfmu slaves (:mod:`.slaves`), the two builds (:mod:`.build_pythonfmu`,
:mod:`.build_native`) and compiled CasADi C called through ctypes (:mod:`.compiled`)."""
