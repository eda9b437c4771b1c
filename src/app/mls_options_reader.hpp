#pragma once
// Reads the MLS keys shared by `mls_fit:` and `efg:` (basis, weight, support) into mls::MlsOptions.
#include "io/yaml_reader.hpp"
#include "mls/mls_shape_functions.hpp"

namespace lamina::app {

mls::MlsOptions read_mls_options(const io::NodeReader& section, int dimension);

}  // namespace lamina::app
