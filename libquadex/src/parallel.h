// Index-parallel loop shared by the quad metrics and the quad relaxation. Internal to libquadex.
#pragma once

#include <cstddef>

#ifdef QUADIFY_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#endif

namespace quadify::quadex {

// Runs body(i) for i in [0, n), in parallel when TBB is available. Each i writes only its own
// output slot, so the result does not depend on the scheduling.
template <class Body>
void parallel_for_each_index(std::size_t n, const Body& body) {
#ifdef QUADIFY_WITH_TBB
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                    });
#else
  for (std::size_t i = 0; i < n; ++i) body(i);
#endif
}

}  // namespace quadify::quadex
