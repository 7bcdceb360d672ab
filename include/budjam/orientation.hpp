#pragma once
// The axis n̂ = (cos θ, sin θ) of a dumbbell with orientation θ.
//
// Lobes sit at centroid ∓ ℓ n̂, so every force evaluation turns the θ of each cell that moved into
// its axis; with the scalar sincos of the C library that was a fifth of a growth run (perf,
// L = 40). Here the axes are computed several cells at a time by glibc's vector maths library
// (libmvec, x86-64: four lanes with AVX2, else two with SSE2), within 4 ulp of the exact values.
// Lobe positions and lever arms are computed from these functions everywhere (the force field,
// place_lobes, contact stresses, the Hessian, the moduli), so they agree bit for bit wherever they
// are computed, and axis(θ) is what axes() gives for the same θ. The vector path is chosen once per
// process from the processor's instruction set (as the C library's scalar sincos picks its FMA
// variant), so a run is reproduced bit for bit on machines of the same instruction set. Built
// without libmvec (other C libraries or processors), both use std::cos and std::sin.
#include <cstddef>

namespace budjam {

struct Axis {
  double c, s;  // cos θ, sin θ
};

Axis axis(double theta);

// c[k] = cos θ[k], s[k] = sin θ[k] for k < n.
void axes(const double* theta, std::size_t n, double* c, double* s);

}  // namespace budjam
