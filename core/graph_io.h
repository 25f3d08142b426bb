// Reading and writing graphs: g2o 2D, TORO, and the GTSAM-style files of
// ../shared/data (see its README and third_party_notes/datasets.md).
//
// Vertex lines (VERTEX_SE2, VERTEX_XY, VERTEX2) are read here; every other
// line is handed to the factor kind the Registry holds for (format, tag),
// so a plugin's factor is readable from files like a built-in one.
//
// Information conventions (each explicit, see information.h):
//   g2o    EDGE_SE2 a b dx dy dth I11 I12 I13 I22 I23 I33  (information)
//   toro   EDGE2    a b dx dy dth I11 I12 I22 I33 I13 I23  (information)
//   gtsam  EDGE2 / ODOMETRY a b dx dy dth c11 c12 c13 c22 c23 c33 (covariance)
//          LANDMARK pose lm x y c11 c12 c22               (covariance)
//
// Format detection (Format::kAuto): a .g2o name or g2o tags -> g2o; a .toro
// name -> toro; ODOMETRY or LANDMARK lines -> gtsam. EDGE2 in any other file
// is ambiguous (TORO information or GTSAM covariance) and is an error that
// asks for an explicit format.
#pragma once

#include <iosfwd>
#include <set>
#include <string>
#include <vector>

#include "core/graph.h"
#include "core/registry.h"

namespace hamal {

enum class Format { kAuto, kG2o, kToro, kGtsam };
// "auto", "g2o", "toro", "gtsam"; throws hamal::Error otherwise.
Format parseFormat(const std::string& name);
const char* formatName(Format format);

// Throws hamal::Error("file:line: reason") on anything it cannot read
// exactly: a missing file, an empty one, an unknown tag, a truncated or
// malformed line, NaN/inf, a matrix that is not SPD, a duplicate vertex id,
// an edge to a variable that no vertex defines (when the file has vertices).
Graph readGraph(const std::string& path, const Registry& registry, Format format = Format::kAuto);
Graph readGraph(std::istream& in, const std::string& name, const Registry& registry, Format format);

// Writes g2o: one vertex line per variable of `values` (sorted by key), a
// FIX line for the `fixed` variables (sorted), then one line per factor
// (Factor::tag + writeFields), with full precision so
// that reading the file back gives the same graph. Throws hamal::Error when
// two variables of different kinds share an index (g2o has one id space).
// Also refuses, before writing anything, what would read back as another
// graph: a variable that is not a Pose2 x<id> or a Point2 l<id>, and a factor
// naming a variable that `values` lacks while `values` is not empty (a g2o
// file lists a vertex for every variable or for none), and a fixed variable
// that neither `values` nor a factor names. The path version
// writes through OutputFile (core/output_file.h): a failed write leaves the
// old file, and a device or FIFO is written in place, never replaced.
void writeG2o(const std::string& path, const Values& values, const std::vector<FactorPtr>& factors,
              const std::set<Key>& fixed = {});
void writeG2o(std::ostream& out, const Values& values, const std::vector<FactorPtr>& factors,
              const std::set<Key>& fixed = {});

// Writes `format`. g2o as writeG2o. TORO and GTSAM's format hold pose
// graphs only: one VERTEX2 line per pose, one EDGE2 line per factor from
// the relative-pose measurement it gives (RelativePoseMeasurement), with the
// information in TORO's layout (I11 I12 I22 I33 I13 I23) or as GTSAM's
// covariance (c11 c12 c13 c22 c23 c33, its inverse). Refused, naming it,
// before anything is written: a landmark, a factor that gives no relative
// pose or carries a robust loss (neither file has a line for it), and a
// fixed variable (neither has FIX). Read back with the same format, a graph
// of thesis-residual between factors is the same graph (the covariance to
// rounding). kAuto is an error.
void writeGraph(const std::string& path, const Values& values,
                const std::vector<FactorPtr>& factors, Format format,
                const std::set<Key>& fixed = {});
void writeGraph(std::ostream& out, const Values& values, const std::vector<FactorPtr>& factors,
                Format format, const std::set<Key>& fixed = {});

}  // namespace hamal
