# Benchmarks of fluid/surface.
