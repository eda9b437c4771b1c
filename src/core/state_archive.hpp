#pragma once
// StateArchive: the state of an incremental analysis as a flat list of named records (numbers,
// integer and real arrays, matrices, text), the payload of a checkpoint (io/checkpoint_file.hpp).
// A reader finds each record by name and checks its kind and shape, so a checkpoint written by a
// different case or build is refused with the name of the record that does not fit.
#include <Eigen/Dense>

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/types.hpp"

namespace lamina {

/// A checkpoint payload that cannot be read or does not fit the analysis reading it.
class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Appends named records to a byte buffer (little-endian host layout; the file header states it).
class StateWriter {
 public:
  void put(const std::string& name, Real value) { put_reals(name, &value, 1, 1, 1); }
  void put(const std::string& name, std::int64_t value) { put_integers(name, &value, 1); }
  void put(const std::string& name, int value) { put(name, static_cast<std::int64_t>(value)); }
  void put(const std::string& name, bool value) { put(name, static_cast<std::int64_t>(value)); }
  void put(const std::string& name, const std::string& text);
  void put(const std::string& name, const char* text) { put(name, std::string(text)); }
  void put(const std::string& name, const std::vector<Real>& values) {
    put_reals(name, values.data(), values.size(), static_cast<std::uint64_t>(values.size()), 1);
  }
  void put(const std::string& name, const std::vector<int>& values);
  void put(const std::string& name, const std::vector<std::int64_t>& values) {
    put_integers(name, values.data(), values.size());
  }
  /// Any dense real matrix or vector (stored column-major with its shape).
  template <class Derived>
  void put_matrix(const std::string& name, const Eigen::DenseBase<Derived>& matrix) {
    const Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic> m = matrix;
    put_reals(name, m.data(), static_cast<std::size_t>(m.size()), static_cast<std::uint64_t>(m.rows()),
              static_cast<std::uint64_t>(m.cols()));
  }
  /// One call for any stored type (an analysis lists its state once, for writing and reading alike).
  template <class T>
  void field(const std::string& name, const T& value) {
    if constexpr (std::is_base_of_v<Eigen::EigenBase<T>, T>) put_matrix(name, value);
    else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) put(name, static_cast<std::int64_t>(value));
    else put(name, value);
  }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  void put_reals(const std::string& name, const Real* data, std::size_t count, std::uint64_t rows, std::uint64_t cols);
  void put_integers(const std::string& name, const std::int64_t* data, std::size_t count);
  void header(const std::string& name, char kind, std::uint64_t rows, std::uint64_t cols);
  void raw(const void* data, std::size_t size);
  std::vector<char> bytes_;
};

/// Parses a payload written by StateWriter; every accessor throws StateError naming the record.
class StateReader {
 public:
  /// Throws StateError when the buffer is not a well-formed sequence of records.
  explicit StateReader(std::vector<char> bytes);

  bool has(const std::string& name) const { return records_.count(name) > 0; }
  std::vector<std::string> names() const;
  Real real(const std::string& name) const;
  std::int64_t integer(const std::string& name) const;
  bool boolean(const std::string& name) const { return integer(name) != 0; }
  std::string text(const std::string& name) const;
  std::vector<Real> reals(const std::string& name) const;
  std::vector<std::int64_t> integers(const std::string& name) const;
  std::vector<int> ints(const std::string& name) const;
  /// A matrix of any shape.
  Eigen::MatrixXd matrix(const std::string& name) const;
  /// Into a matrix of the shape the analysis already has (set up before restoring): refused otherwise,
  /// and refused when a value is not finite (an analysis stops before its state goes non-finite).
  template <class Derived>
  void matrix_into(const std::string& name, Eigen::PlainObjectBase<Derived>& into) const {
    const Eigen::MatrixXd m = matrix(name);
    const bool rows_fit = m.rows() == into.rows(), cols_fit = m.cols() == into.cols();
    if (!rows_fit || !cols_fit) shape_error(name, m.rows(), m.cols(), into.rows(), into.cols());
    if (!m.allFinite()) throw StateError("checkpoint record '" + name + "' holds a non-finite value");
    into = m;
  }
  /// The counterpart of StateWriter::field (matrices must have their size already).
  template <class T>
  void field(const std::string& name, T& value) const {
    if constexpr (std::is_base_of_v<Eigen::EigenBase<T>, T>) matrix_into(name, value);
    else if constexpr (std::is_same_v<T, Real>) value = real(name);
    else if constexpr (std::is_same_v<T, bool>) value = boolean(name);
    else if constexpr (std::is_same_v<T, std::string>) value = text(name);
    else if constexpr (std::is_same_v<T, std::vector<Real>>) value = reals(name);
    else if constexpr (std::is_same_v<T, std::vector<int>>) value = ints(name);
    else if constexpr (std::is_integral_v<T>) value = static_cast<T>(integer(name));
    else static_assert(sizeof(T) == 0, "no checkpoint record type for this field");
  }

 private:
  struct Record {
    char kind = 0;
    std::uint64_t rows = 0, cols = 0;
    std::size_t offset = 0;  // of the data in bytes_
  };
  const Record& find(const std::string& name, char kind) const;
  [[noreturn]] static void shape_error(const std::string& name, Index rows, Index cols, Index want_rows, Index want_cols);
  std::vector<char> bytes_;
  std::map<std::string, Record, std::less<>> records_;
};

}  // namespace lamina
