# Benchmarks of fluid/collide.
