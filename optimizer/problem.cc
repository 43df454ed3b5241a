#include "optimizer/problem.h"

#include <stdexcept>

#include "optimizer/joints.h"

namespace tangent::optimizer {

Problem::Problem(Mechanism mechanism) : mechanism_(std::move(mechanism)) {
  for (int i = 0; i < mechanism_.num_bodies(); ++i) {
    if (mechanism_.offset(i) >= 0) AddEquality(UnitQuaternion(i));
  }
}

int Problem::Add(std::vector<Entry>* list, int* rows, TermPtr term, double weight) {
  if (!term) throw std::invalid_argument("problem: null term");
  for (int b : {term->body_a(), term->body_b()}) {
    if (b >= mechanism_.num_bodies() || b < -1) {
      throw std::invalid_argument("problem: term \"" + term->name() + "\" refers to body " +
                                  std::to_string(b) + " of " +
                                  std::to_string(mechanism_.num_bodies()));
    }
  }
  if (term->body_a() < 0) {
    throw std::invalid_argument("problem: term \"" + term->name() + "\" has no body");
  }
  if (!(weight >= 0.0) || !std::isfinite(weight)) {
    throw std::invalid_argument("problem: term \"" + term->name() + "\" has an invalid weight");
  }
  list->push_back({std::move(term), weight, *rows});
  *rows += list->back().term->dim();
  return static_cast<int>(list->size()) - 1;
}

int Problem::AddEquality(TermPtr term) { return Add(&equalities_, &rows_e_, std::move(term), 1.0); }
int Problem::AddInequality(TermPtr term) {
  return Add(&inequalities_, &rows_i_, std::move(term), 1.0);
}
void Problem::AddDesignObjective(std::shared_ptr<const DesignObjective> f, double weight) {
  if (!f) throw std::invalid_argument("problem: null design objective");
  if (!(weight >= 0.0) || !std::isfinite(weight)) {
    throw std::invalid_argument("problem: design objective \"" + f->name() +
                                "\" has an invalid weight");
  }
  design_.push_back({std::move(f), weight});
}

int Problem::AddObjective(TermPtr term, double weight) {
  return Add(&objectives_, &rows_o_, std::move(term), weight);
}

ProblemData::ProblemData(const Problem& problem) {
  const std::vector<Problem::Entry>* lists[3] = {&problem.equalities(), &problem.inequalities(),
                                                 &problem.objectives()};
  for (size_t k = 0; k < 3; ++k) {
    for (const Problem::Entry& e : *lists[k]) {
      states_[k].push_back(e.term->MakeState());
      if (states_[k].back()) index_.emplace_back(e.term.get(), states_[k].back().get());
    }
  }
}

}  // namespace tangent::optimizer
