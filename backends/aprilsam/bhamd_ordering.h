// The orderings AprilSAM's min-heap ordering is compared with (thesis
// sec. 3.5.1): BHAMD with the newest node last, for the NoPredictiveOrder
// variant, and SuiteSparse's AMD.
//
// BHAMD (Agarwal & Olson's bucket-heap approximate minimum degree) is
// implemented here as the thesis describes it against its own ordering
// (sec. 3.4.3): the same min-heap of score lists and the same approximate
// elimination-graph degree as minHeapOrdering, but a node's list is checked
// only when that list is extracted (Rescoring::kOnExtraction), so a node
// whose degree fell through a neighbour's removal stays in its higher list.
// This keeps the two orderings identical except for the one difference the
// thesis claims matters, so the NoPredictiveOrder ablation measures it.
#pragma once

#include <vector>

#include "backends/aprilsam/ordering_input.h"

namespace hamal::aprilsam {

// Newest node last (when in.newest >= 0), BHAMD on the rest.
std::vector<int> bhamdOrdering(const OrderingInput& in);

// SuiteSparse amd_order (default controls) on the node graph; ignores
// in.newest. Throws hamal::Error on a bad input or when AMD fails.
std::vector<int> amdOrdering(const OrderingInput& in);

}  // namespace hamal::aprilsam
