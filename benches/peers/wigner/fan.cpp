// Peer-comparison driver for the Wigner mirage simulator (B. Bamer,
// github.com/balazs-bamer/simple-polynomial-mirage, see README.md).
//
// Traces the 1000-ray fan of reference.py with the upstream
// RungeKuttaRayBending::solve4x, using the upstream defaults of its 2-D CLI
// (eikonal.cpp): RKF45, tolAbs = tolRel = 1e-3, step1 = 0.01 m,
// stepMin = 1e-7 m, stepMax = 22.2 m, maxCosDirChange = 0.99999999999,
// distAlongRay = 2 * dist; water model with tempAmb = 10, tempBase = 13
// (T = 10.033 + 3.15 exp(-20.1 h)), flat earth.
//
// Output (stdout): '#' comment lines with timing, then one line per ray:
//   index angle_deg valid x y dir_angle_deg
// where (x, y) is what solve4x returns (x slightly >= 3000: upstream stops
// after the first step that crosses x) and dir_angle_deg is the angle of the
// returned direction. compare.py turns this into errors against
// fan_reference.json.
//
// Built with -DCOUNT_RHS (see build.sh) against a copy of Eikonal.h whose
// differentials() increments g_rhs_evals, it also reports RHS evaluations.
#include "RungeKuttaRayBending.h"
#include "Eikonal.h"
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#ifdef COUNT_RHS
unsigned long long g_rhs_evals = 0;
#endif

int main(int argc, char **argv) {
  CLI::App app{"Wigner mirage solve4x fan driver"};
  double xTarget = 3000.0, camHeight = 1.1, a0 = -0.04, a1 = -0.14;
  unsigned count = 1000, reps = 5;
  RungeKuttaRayBending::Parameters par;
  par.mStepper = StepperType::cRungeKuttaFehlberg45;
  par.mTolAbs = 1e-3;
  par.mTolRel = 1e-3;
  par.mStep1 = 0.01;
  par.mStepMin = 1e-7;
  par.mStepMax = 22.2;
  par.mMaxCosDirChange = 0.99999999999;
  std::vector<double> extra;  // extra single rays, e.g. steeper than critical
  app.add_option("--dist", xTarget, "x target (m)");
  app.add_option("--camCenter", camHeight, "start height (m)");
  app.add_option("--count", count, "rays in the fan");
  app.add_option("--reps", reps, "timing repetitions (best is reported)");
  app.add_option("--tolAbs", par.mTolAbs, "absolute tolerance [1e-3]");
  app.add_option("--tolRel", par.mTolRel, "relative tolerance [1e-3]");
  app.add_option("--stepMax", par.mStepMax, "step cap (m) [22.2]");
  app.add_option("--extra", extra, "extra single-ray angles (deg) to report");
  CLI11_PARSE(app, argc, argv);
  par.mDistAlongRay = 2.0 * xTarget;  // as eikonal.cpp

  Eikonal eikonal(Eikonal::EarthForm::cFlat, 6371000.0, Eikonal::Model::cWater, 10.0, 10.0, 10.0, 13.0);
  RungeKuttaRayBending rk(par, eikonal);

  // numpy.linspace(a0, a1, count)
  std::vector<double> angles(count);
  double step = (a1 - a0) / (count - 1);
  for (unsigned i = 0; i < count; ++i) angles[i] = i * step + a0;
  angles[count - 1] = a1;

  auto trace = [&](double deg) {
    double r = deg / 180.0 * cgPi;  // upstream converts the same way
    Vertex start(0.0, camHeight, 0.0);
    Vector dir(std::cos(r), std::sin(r), 0.0);
    return rk.solve4x(start, dir, xTarget);
  };

  std::vector<RungeKuttaRayBending::Result> res(count);
  double best = 1e300;
#ifdef COUNT_RHS
  reps = 1;
#endif
  for (unsigned rep = 0; rep < reps; ++rep) {
    auto t0 = std::chrono::steady_clock::now();
    for (unsigned i = 0; i < count; ++i) res[i] = trace(angles[i]);
    double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("# rep %u: %.6f s, %.1f rays/s\n", rep, dt, count / dt);
    if (dt < best) best = dt;
  }
  std::printf("# best: %.6f s for %u rays = %.1f rays/s (%.2f us/ray)\n", best, count, count / best, 1e6 * best / count);
#ifdef COUNT_RHS
  std::printf("# rhs evaluations: %llu total, %.1f per ray\n", g_rhs_evals, double(g_rhs_evals) / count);
#endif
  unsigned invalid = 0;
  for (unsigned i = 0; i < count; ++i) invalid += !res[i].mValid;
  std::printf("# invalid (mValid == false): %u\n", invalid);
  for (double deg : extra) {
#ifdef COUNT_RHS
    unsigned long long before = g_rhs_evals;
#endif
    auto r = trace(deg);
    std::printf("# extra %.6g deg: valid %d x %.10g y %.10g dir %.10g deg", deg, int(r.mValid), r.mValue(0), r.mValue(1),
                std::atan2(r.mDirection(1), r.mDirection(0)) * 180.0 / cgPi);
#ifdef COUNT_RHS
    std::printf(" rhs %llu", g_rhs_evals - before);
#endif
    std::printf("\n");
  }
  for (unsigned i = 0; i < count; ++i) {
    auto const &r = res[i];
    std::printf("%u %.17g %d %.17g %.17g %.17g\n", i, angles[i], int(r.mValid), r.mValue(0), r.mValue(1),
                std::atan2(r.mDirection(1), r.mDirection(0)) * 180.0 / cgPi);
  }
  return 0;
}
