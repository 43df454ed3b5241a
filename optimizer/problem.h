#pragma once

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
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
  /// Weighted objective ½ w |r(q)|² (w ≥ 0).
  int AddObjective(TermPtr term, double weight);
  /// Design objective to maximize with weight w ≥ 0 (E −= w f). Not for the servo loop: the
  /// objectives provided (Dexterity) allocate.
  void AddDesignObjective(std::shared_ptr<const DesignObjective> f, double weight);
  struct DesignEntry {
    std::shared_ptr<const DesignObjective> f;
    double weight = 1.0;
  };
  const std::vector<DesignEntry>& design_objectives() const { return design_; }
  /// Weight of least astonishment (0 disables it). Like the Add* calls, a building step: a
  /// Problem is built, then only read (solvers and threads hold it const).
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

/// The per-solve data of a Problem: one TermState per term entry that has one (tracked contact
/// parameters, goal targets, scratch), made once. The Problem and its terms are not changed by a
/// solve, so one problem may be solved on several threads at once, each with its own data (each
/// Solver owns one, through its ProblemEvaluator).
class ProblemData {
 public:
  explicit ProblemData(const Problem& problem);
  ProblemData(const ProblemData&) = delete;
  ProblemData& operator=(const ProblemData&) = delete;

  /// The state of entry `index` of a kind (0 equalities, 1 inequalities, 2 objectives), or
  /// nullptr for a stateless term.
  TermState* state(int kind, int index) const {
    TANGENT_DCHECK(kind >= 0 && kind < 3 && index >= 0 &&
                   static_cast<size_t>(index) < states_[static_cast<size_t>(kind)].size());
    return states_[static_cast<size_t>(kind)][static_cast<size_t>(index)].get();
  }
  /// The state of `term`, which must be an entry of the problem with a state of type T::State.
  /// A lookup over the entries: callers on the servo path keep the reference.
  /// @throws std::invalid_argument naming the term otherwise.
  template <class T>
  typename T::State& Of(const T& term) {
    return StateAs<typename T::State>(term);
  }
  /// The state of entry `term` as type S (for a term that wraps another, e.g. Shifted).
  template <class S>
  S& StateAs(const Term& term) {
    for (const auto& [t, st] : index_) {
      if (t != &term) continue;
      if (auto* typed = dynamic_cast<S*>(st)) return *typed;
    }
    throw std::invalid_argument("problem data: no state for term '" + term.name() + "'");
  }
  /// Whether `term` is an entry of the problem with a state.
  bool HasState(const Term& term) const {
    for (const auto& [t, st] : index_) {
      if (t == &term) return true;
    }
    return false;
  }

 private:
  std::array<std::vector<std::unique_ptr<TermState>>, 3> states_;
  std::vector<std::pair<const Term*, TermState*>> index_;
};

}  // namespace tangent::optimizer
