#pragma once
// J. C. Martin & W. J. Moyce 1952, "An experimental study of the collapse of liquid columns on a
// rigid horizontal plane", Phil. Trans. R. Soc. A 244, 312-324, figure 3: the surge front
// Z = x / a against T = t sqrt(2 g / a) for a column of water of width a = 2.25 in (0.05715 m) and
// height 2a (n^2 = 2). The points are that figure's, as digitised for the PySPH project's
// dam-break examples (pysph/examples/db_exp_data.py). Used by tests/sph and bench_sph front.
#include <array>

namespace fluid_test {

struct FrontPoint {
  double t_scaled;  // T = t sqrt(2 g / a)
  double front;     // Z = x / a
};
inline constexpr double kMartinMoyceWidth = 0.05715;  // a (m): 2.25 in
inline constexpr std::array<FrontPoint, 10> kMartinMoyce2a = {{{0.832, 1.217},
                                                               {1.219, 1.474},
                                                               {1.997, 2.292},
                                                               {2.547, 2.995},
                                                               {3.345, 4.134},
                                                               {4.034, 4.944},
                                                               {4.418, 5.881},
                                                               {5.091, 6.980},
                                                               {5.685, 7.945},
                                                               {6.306, 8.966}}};

}  // namespace fluid_test
