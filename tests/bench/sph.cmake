# Benchmarks of fluid/sph.
