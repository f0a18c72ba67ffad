// Clusters of paper 2 (Sumita, Kiyama & Nishimura): discs bound into one body. The contacts
// inside a cluster ignore paper 1's two conditions (no tension, Coulomb cap): both springs act in
// tension and without limit, with their dashpots. Every other contact follows paper 1's law.
//
// A bonded pair is not a neighbour-list contact: it lives in its own fixed list (World::bonds)
// with its own history, and stays there when the discs separate. Its law is contact_law.hpp's
// bond_law. Bonds are a feature of the kernel list (kernels.hpp): a scene without clusters runs
// a kernel without bond code.
#pragma once

#include <string>
#include <vector>

#include "physics/discs.hpp"

namespace dem {

// Which pairs of a cluster are bonded.
enum class BondSet {
  all,       // every pair of the cluster (a 3-disc cluster is a closed triangle: one elastic body)
  touching   // the pairs whose gap is at most touch_tolerance when bonded (the paper's
             // "inter-element contacts"; a 3-disc lattice cluster with alpha < 60 deg is then a V)
};

struct ClusterSpec {
  bool enabled = false;
  BondSet bonds = BondSet::all;
  double touch_tolerance = 0.01;          // [cm]
  std::vector<std::vector<int>> members;  // disc indices (fill order), one list per cluster
};

// One bonded pair. The bond point divides the centre line in the ratio r_i : r_j; its lever arms
// are a_i = r_i max(1, R0/(r_i + r_j)) (= r_i for touching discs, as in eq. 5b), so that a rigid
// rotation of the pair gives no shear increment. Springs start at 0 in the bonded configuration.
struct Bond {
  int i = 0, j = 0;           // disc indices, i < j
  double ai = 0, aj = 0;      // lever arms [cm]
  double rest = 0;            // centre distance when bonded [cm]
  double en = 0, es = 0;      // elastic normal (negative: tension) and shear forces
  double fn = 0, fs = 0;      // totals with the dashpots
};

// Bonds of the clusters over the discs (sorted by (i, j)). Throws std::invalid_argument naming the
// cluster when a disc index is out of range, a disc is in two clusters, a cluster has fewer than
// two discs, or (touching) a cluster is not connected by its touching pairs.
std::vector<Bond> make_bonds(const Discs& d, const ClusterSpec& spec);

// Cluster index of each disc (-1: free disc).
std::vector<int> cluster_of_discs(std::size_t n_discs, const ClusterSpec& spec);

// Largest |R - R0| / R0 over the bonds (internal deformation of the clusters).
double max_bond_strain(const Discs& d, const std::vector<Bond>& bonds);

const char* to_string(BondSet b);

}  // namespace dem
