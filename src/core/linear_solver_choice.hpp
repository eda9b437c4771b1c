#pragma once
// LinearSolverChoice: the case's `solver: {type: cholmod | mumps | cg, preconditioner: gamg | hypre}`
// (PRODUCT.md section 5) for the linear solves of efg, mpfem and pd: CHOLMOD on one process (the default
// there), PETSc's MUMPS or preconditioned CG (the default on several ranks: MUMPS).
#include <string>

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/types.hpp"

namespace lamina {

struct LinearSolverChoice {
  enum class Type { automatic, cholmod, mumps, cg };
  enum class Preconditioner { gamg, hypre };
  Type type = Type::automatic;               // automatic: cholmod on one process, mumps on several
  Preconditioner preconditioner = Preconditioner::gamg;
  Real relative_tolerance = 1e-10;           // cg: |r| / |b|
  int max_iterations = 10000;                // cg

  /// Whether the solve goes through PETSc: on several ranks, or when mumps / cg is asked for.
  bool uses_petsc(bool distributed) const { return distributed || type == Type::mumps || type == Type::cg; }
  /// Several ranks with `solver: {type: cholmod}` given: SingleProcessOnly (CHOLMOD runs on one process).
  void check_ranks(int ranks) const {
    if (ranks > 1 && type == Type::cholmod)
      throw SingleProcessOnly("solver.type", fmt::format("mumps or cg on {} ranks (cholmod runs on one process)", ranks),
                              "cholmod");
  }
};

inline const char* name_of(LinearSolverChoice::Type t) {
  switch (t) {
    case LinearSolverChoice::Type::cholmod: return "cholmod";
    case LinearSolverChoice::Type::mumps: return "mumps";
    case LinearSolverChoice::Type::cg: return "cg";
    default: return "automatic";
  }
}

}  // namespace lamina
