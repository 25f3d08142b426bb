// parallelFor: the one way MOSS spreads independent work (trials, hill
// climbs, thesis ch. 5) over threads. An exception thrown by the work on any
// thread stops the handing out of further items and is rethrown to the
// caller once every thread has joined, so bad input inside a worker is the
// caller's hamal::Error, never std::terminate.
#pragma once

#include <functional>

namespace hamal::moss {

// Calls body(k) for every k in [0, count), on max(1, min(threads, count))
// threads; rethrows the first exception any call threw.
void parallelFor(int threads, int count, const std::function<void(int)>& body);

}  // namespace hamal::moss
