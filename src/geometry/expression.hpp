#pragma once
// A scalar expression of the reference coordinates x, y, z (and r = sqrt(x^2+y^2),
// theta = atan2(y,x)) and time t, parsed once with muParser; `and or not` words are accepted.
#include <memory>
#include <string>

#include "core/types.hpp"

namespace lamina::geometry {

class Expression {
 public:
  /// Parses `text`; throws ExpressionError (with the position) if it is not a valid expression.
  explicit Expression(const std::string& text);
  ~Expression();
  Expression(Expression&&) noexcept;
  Expression& operator=(Expression&&) noexcept;
  Expression(const Expression& other);
  Expression& operator=(const Expression& other);

  /// Value at a point and time. Not thread-safe: use one Expression per thread.
  Real evaluate(const Vec3& x, Real t = 0.0) const;
  const std::string& text() const { return text_; }

 private:
  struct Impl;
  std::string text_;
  std::unique_ptr<Impl> impl_;
};

class ExpressionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A value that is either a constant or an Expression of x, y, z, t.
struct ScalarField {
  Real constant = 0.0;
  std::string expression;  // empty => constant
  bool is_constant() const { return expression.empty(); }
};

/// A ScalarField parsed once and evaluated at many points at one time t (serial use: one per thread).
class FieldEvaluator {
 public:
  FieldEvaluator(const ScalarField& field, Real t);
  Real operator()(const Vec3& x) const { return expression_ ? expression_->evaluate(x, t_) : constant_; }

 private:
  Real constant_, t_;
  std::unique_ptr<Expression> expression_;
};

}  // namespace lamina::geometry
