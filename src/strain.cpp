#include "budjam/strain.hpp"

#include "budjam/energy.hpp"
#include "budjam/moduli.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace budjam {

void apply_simple_shear(Packing& p, double dgamma) {
  p.box.shear += dgamma;
  for (std::size_t i = 0; i < p.size(); ++i) p.q[3 * i] += dgamma * p.q[3 * i + 1];
}

void apply_isotropic_scaling(Packing& p, double factor) {
  if (!(factor > 0)) throw std::invalid_argument("apply_isotropic_scaling: factor must be positive");
  p.box.L *= factor;
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.q[3 * i] *= factor;
    p.q[3 * i + 1] *= factor;
  }
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs(const std::vector<Contact>& contacts) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(contacts.size());
  for (const Contact& c : contacts) pairs.emplace_back(std::min(c.i, c.j), std::max(c.i, c.j));
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

namespace {

struct Measured {
  StrainSample sample;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
};

Measured relax_and_measure(Packing& p, const FireParams& fire, double skin) {
  ForceField field(skin);
  Measured m;
  m.sample.fire = minimise(p, field, fire);
  Eigen::VectorXd F;
  m.sample.U = field.evaluate(p, F);
  const auto contacts = find_contacts(p, field.lobes(), field.neighbours());
  m.sample.P = pressure(contacts, p.box);
  m.sample.stress = stress_tensor(contacts, p.box);
  m.sample.stress_energy = energy_stress(p, contacts);
  m.sample.stress_link = link_stress(p, contacts);
  m.sample.P_energy = -0.5 * m.sample.stress_energy.trace();
  m.pairs = contact_pairs(contacts);
  return m;
}

// Least-squares polynomial fit of degree `deg`; returns coefficients c0..c_deg. The abscissae are
// scaled to [−1, 1] first: strains of 1e-10 would make the x² column fall below the rank threshold.
Eigen::VectorXd polyfit(const std::vector<double>& x, const std::vector<double>& y, int deg) {
  double scale = 0;
  for (double v : x) scale = std::max(scale, std::abs(v));
  if (scale == 0) scale = 1;
  Eigen::MatrixXd V(static_cast<Eigen::Index>(x.size()), deg + 1);
  Eigen::VectorXd Y(static_cast<Eigen::Index>(x.size()));
  for (std::size_t k = 0; k < x.size(); ++k) {
    double pw = 1;
    for (int d = 0; d <= deg; ++d, pw *= x[k] / scale) V(static_cast<Eigen::Index>(k), d) = pw;
    Y[static_cast<Eigen::Index>(k)] = y[k];
  }
  Eigen::VectorXd c = V.colPivHouseholderQr().solve(Y);
  for (int d = 1; d <= deg; ++d) c[d] /= std::pow(scale, d);
  return c;
}

}  // namespace

std::vector<double> symmetric_strains(double h, int count) {
  std::vector<double> s;
  for (int k = count; k >= 1; --k) s.push_back(-k * h);
  for (int k = 1; k <= count; ++k) s.push_back(k * h);
  return s;
}

std::vector<double> doubling_strains(double h, int count) {
  std::vector<double> s;
  for (int k = count - 1; k >= 0; --k) s.push_back(-std::ldexp(h, k));
  for (int k = 0; k < count; ++k) s.push_back(std::ldexp(h, k));
  return s;
}

StrainSweep strain_sweep(const Packing& reference, StrainKind kind, const std::vector<double>& strains,
                         const FireParams& fire, double skin) {
  StrainSweep sweep;
  sweep.kind = kind;
  Packing ref = reference;
  Measured m0 = relax_and_measure(ref, fire, skin);
  m0.sample.strain = 0;
  std::vector<StrainSample> samples{m0.sample};
  for (double s : strains) {
    if (s == 0) continue;
    Packing p = ref;
    if (kind == StrainKind::simple_shear)
      apply_simple_shear(p, s);
    else
      apply_isotropic_scaling(p, std::exp(0.5 * s));
    Measured m = relax_and_measure(p, fire, skin);
    m.sample.strain = s;
    m.sample.same_contacts = (m.pairs == m0.pairs);
    samples.push_back(m.sample);
  }
  std::sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.strain < b.strain; });
  sweep.samples = samples;

  std::vector<double> x, y, ye, u;
  for (const auto& s : sweep.samples) {
    sweep.all_converged = sweep.all_converged && s.fire.converged;
    if (!s.same_contacts) continue;
    x.push_back(s.strain);
    u.push_back(s.U);
    if (kind == StrainKind::simple_shear) {
      y.push_back(s.stress(0, 1));
      ye.push_back(0.5 * (s.stress_energy(0, 1) + s.stress_energy(1, 0)));
    } else {
      y.push_back(-s.P);
      ye.push_back(-s.P_energy);
    }
  }
  sweep.used = x.size();
  if (x.size() >= 2) {
    sweep.modulus = polyfit(x, y, 1)[1];
    sweep.modulus_energy = polyfit(x, ye, 1)[1];
  }
  const double A = reference.box.L * reference.box.L;
  // A curvature at s = 0 from samples on one side only extrapolates the parabola to the reference,
  // where the rounding of U (∝ 1/s²) is not cancelled: it needs a kept sample on either side.
  const bool bracketed = std::any_of(x.begin(), x.end(), [](double s) { return s < 0; }) &&
                         std::any_of(x.begin(), x.end(), [](double s) { return s > 0; });
  if (x.size() >= 3 && bracketed) {
    const Eigen::VectorXd c = polyfit(x, u, 2);
    sweep.energy_slope = c[1] / A;
    sweep.curvature = 2.0 * c[2] / A;
  }
  // Central second differences about the relaxed reference (samples sorted by strain).
  const auto zero =
      std::find_if(sweep.samples.begin(), sweep.samples.end(), [](const auto& s) { return s.strain == 0; });
  for (const StrainSample& plus : sweep.samples) {
    if (!(plus.strain > 0) || !plus.same_contacts) continue;
    const auto minus = std::find_if(sweep.samples.begin(), sweep.samples.end(),
                                    [&](const auto& s) { return s.strain == -plus.strain && s.same_contacts; });
    if (minus == sweep.samples.end()) continue;
    const double h = plus.strain;
    sweep.central_curvatures.emplace_back(h, (plus.U - 2 * zero->U + minus->U) / (A * h * h));
  }
  return sweep;
}

}  // namespace budjam
