"""The FMUs: the one table of their variables (:mod:`.variables`), the per-step Functions both
flavours call (:mod:`.functions`), what runs inside the pythonfmu slaves (:mod:`.slaves`), the
instance wrapper every caller uses (:mod:`.instance`), and the builds: below them the
toolchain (:mod:`.toolchain`) and the modelDescription writer (:mod:`.description`); the
pythonfmu flavour (:mod:`.build_pythonfmu`, with its guard library :mod:`.build_guard`) and
the native one, FMI 2 and 3 (:mod:`.build_native`, :mod:`.build_fmi3`)."""
