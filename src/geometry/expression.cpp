#include "geometry/expression.hpp"

#include <muParser.h>

#include <cmath>
#include <regex>

namespace lamina::geometry {

namespace {

double logical_not(double v) { return v == 0.0 ? 1.0 : 0.0; }
double atan2_function(double y, double x) { return std::atan2(y, x); }

/// Replace the words and / or / not by the operators muParser knows.
std::string translate_words(const std::string& text) {
  static const std::regex and_word(R"(\band\b)"), or_word(R"(\bor\b)"), not_word(R"(\bnot\b)");
  std::string out = std::regex_replace(text, and_word, "&&");
  out = std::regex_replace(out, or_word, "||");
  out = std::regex_replace(out, not_word, "!");
  return out;
}

}  // namespace

struct Expression::Impl {
  mu::Parser parser;
  double x = 0, y = 0, z = 0, t = 0, r = 0, theta = 0;
  bool uses_r = true, uses_theta = true;  // r and theta are computed per evaluation only when the text uses them

  explicit Impl(const std::string& text) {
    parser.DefineVar("x", &x);
    parser.DefineVar("y", &y);
    parser.DefineVar("z", &z);
    parser.DefineVar("t", &t);
    parser.DefineVar("r", &r);
    parser.DefineVar("theta", &theta);
    parser.DefineConst("pi", M_PI);
    parser.DefineFun("atan2", atan2_function);
    parser.DefineInfixOprt("!", logical_not);
    parser.SetExpr(translate_words(text));
    parser.Eval();  // compile now so that errors surface at parse time
    const auto& used = parser.GetUsedVar();
    uses_r = used.count("r") > 0;
    uses_theta = used.count("theta") > 0;
  }
};

Expression::Expression(const std::string& text) : text_(text) {
  if (text.find_first_not_of(" \t") == std::string::npos) throw ExpressionError("empty expression");
  try {
    impl_ = std::make_unique<Impl>(text);
  } catch (const mu::Parser::exception_type& e) {
    throw ExpressionError(e.GetMsg() + " (at character " + std::to_string(e.GetPos() + 1) + " of '" + text + "')");
  }
}

Expression::~Expression() = default;
Expression::Expression(Expression&&) noexcept = default;
Expression& Expression::operator=(Expression&&) noexcept = default;
Expression::Expression(const Expression& other) : Expression(other.text_) {}
Expression& Expression::operator=(const Expression& other) {
  if (this != &other) *this = Expression(other.text_);
  return *this;
}

Real Expression::evaluate(const Vec3& point, Real time) const {
  Impl& p = *impl_;
  p.x = point.x();
  p.y = point.y();
  p.z = point.z();
  p.t = time;
  if (p.uses_r) p.r = std::sqrt(p.x * p.x + p.y * p.y);
  if (p.uses_theta) p.theta = std::atan2(p.y, p.x);
  try {
    return p.parser.Eval();
  } catch (const mu::Parser::exception_type& e) {
    throw ExpressionError(e.GetMsg() + " in '" + text_ + "'");
  }
}

FieldEvaluator::FieldEvaluator(const ScalarField& field, Real t) : constant_(field.constant), t_(t) {
  if (!field.is_constant()) expression_ = std::make_unique<Expression>(field.expression);
}

}  // namespace lamina::geometry
