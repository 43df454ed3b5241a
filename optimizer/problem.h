#pragma once

#include <memory>
#include <string>
#include <vector>

#include "optimizer/term.h"

namespace tangent::optimizer {

/// A scalar design objective to maximize, added to a Problem: E −= w f(q). Gradient only (the
/// solver's Newton matrix gets no curvature from it: a damped ascent balanced by least
/// astonishment, which suits design studies; see Dexterity).
class DesignObjective {
 public:
  virtual ~DesignObjective() = default;
  virtual std::string name() const = 0;
  virtual double Value(const Eigen::VectorXd& q) const = 0;
  virtual void Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* g) const = 0;
};

/// minimize E(q) = ½ w_la (q − q_prev)ᵀ M (q − q_prev) + Σ ½ w_k |r_k(q)|²
/// subject to c_E(q) = 0 and c_I(q) ≥ 0 (design.md §4.5). M is the kinetic-energy metric of the
/// mechanism at q_prev (seed 004 "physical justification"), with per-body rigidities (seed 002
/// §11). Every moving body gets the equality |Q|² − 1 = 0 automatically.
class Problem {
 public:
  explicit Problem(Mechanism mechanism);

  const Mechanism& mechanism() const { return mechanism_; }
  /// Hard constraint r(q) = 0. @return its index among equalities.
  int AddEquality(TermPtr term);
  /// Hard constraint r(q) ≥ 0 (componentwise).
  int AddInequality(TermPtr term);
  /// Weighted objective ½ w |r(q)|² (w ≥ 0; change it later with set_weight).
  int AddObjective(TermPtr term, double weight);
  void set_weight(int objective, double w) {
    objectives_[static_cast<size_t>(objective)].weight = w;
  }
  /// Design objective to maximize with weight w ≥ 0 (E −= w f). Not for the servo loop: the
  /// objectives provided (Dexterity) allocate.
  void AddDesignObjective(std::shared_ptr<const DesignObjective> f, double weight);
  struct DesignEntry {
    std::shared_ptr<const DesignObjective> f;
    double weight = 1.0;
  };
  const std::vector<DesignEntry>& design_objectives() const { return design_; }
  /// Weight of least astonishment (0 disables it).
  void set_least_astonishment(double w) { least_astonishment_ = w; }
  double least_astonishment() const { return least_astonishment_; }

  struct Entry {
    TermPtr term;
    double weight = 1.0;
    int row = 0;  ///< first row in the stacked vector of its kind
  };
  const std::vector<Entry>& equalities() const { return equalities_; }
  const std::vector<Entry>& inequalities() const { return inequalities_; }
  const std::vector<Entry>& objectives() const { return objectives_; }
  int num_equality_rows() const { return rows_e_; }
  int num_inequality_rows() const { return rows_i_; }
  int num_objective_rows() const { return rows_o_; }

 private:
  int Add(std::vector<Entry>* list, int* rows, TermPtr term, double weight);

  Mechanism mechanism_;
  std::vector<Entry> equalities_, inequalities_, objectives_;
  std::vector<DesignEntry> design_;
  int rows_e_ = 0, rows_i_ = 0, rows_o_ = 0;
  double least_astonishment_ = 1e-3;
};

}  // namespace tangent::optimizer
