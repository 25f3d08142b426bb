// Checked numpy arguments: every array that crosses into hamal is converted
// here, so a wrong shape, a dtype that is not a real number, or a NaN/inf
// is a hamal.Error naming the argument and the reason, as a bad file line is
// one naming its line (core/error.h), and never reaches a factor or a
// back-end half-read.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <string>

namespace hamal::python {

// `obj` as a C-contiguous float64 array of `rows` x `cols` (cols = 0: a
// vector of `rows`; -1 for either: any size there). Accepts float and
// integer dtypes and nested sequences; throws hamal::Error("name: reason")
// for anything else and for non-finite entries.
pybind11::array_t<double, pybind11::array::c_style> numericArray(pybind11::handle obj,
                                                                 const std::string& name, long rows,
                                                                 long cols);

// A square information matrix: `n` x `n`, finite, symmetric and positive
// definite, or hamal::Error naming `name`.
Eigen::MatrixXd informationMatrix(pybind11::handle obj, const std::string& name, long n);

}  // namespace hamal::python
