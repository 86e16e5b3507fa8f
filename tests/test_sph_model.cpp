// SPH model physics tests (in progress).
