#include "drivetrain_stiffness/core/dynamics/sliced_interval_maps.hpp"

#include <algorithm>
#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

SlicedIntervalMaps::SlicedIntervalMaps(const SlicedMesh& slices, int intervals, double f) : f_(f) {
  if (intervals < 1) throwInvalid("intervals", intervals, "must be at least 1 per mesh period");
  if (!(f > 0.0) || !std::isfinite(f))
    throwInvalid("mesh frequency", f, "must be positive and finite");
  intervals_.resize(static_cast<std::size_t>(intervals));
  for (int i = 0; i < intervals; ++i) {
    // Interval i spans the phases [i/n, (i+1)/n]: its start, every slice boundary strictly inside
    // it, its end (a boundary on the end is the next interval's start).
    const double q0 = static_cast<double>(i) / intervals,
                 q1 = static_cast<double>(i + 1) / intervals;
    Interval& v = intervals_[static_cast<std::size_t>(i)];
    int j = slices.sliceAt(q0, false);
    v.offset.push_back(0.0);
    v.slice.push_back(j);
    while (j + 1 < slices.size() && slices.end(j) < q1) {
      v.offset.push_back(slices.end(j) - q0);
      v.slice.push_back(++j);
    }
    v.offset.push_back(q1 - q0);  // one slice per piece: pieces = boundaries - 1
    v.head.resize(v.offset.size());
    v.tail.resize(v.offset.size());
  }
}

void SlicedIntervalMaps::invalidate() {
  for (Interval& v : intervals_) {
    v.ready = false;
    v.uses = 0;
  }
}

bool SlicedIntervalMaps::available(const SlicedModalPropagator& exact, int i) {
  Interval& v = intervals_[static_cast<std::size_t>(i)];
  if (v.ready) return v.usable;
  // Made on the second use under the same parameters: making them costs about three crossings of
  // the interval slice by slice (header), which a bearing stiffness changing at every interval
  // would pay each time without a use to pay it back.
  if (++v.uses < kUsesBeforeMaking) return false;
  return make(exact, i);
}

int SlicedIntervalMaps::boundaryAtOrBefore(int i, double u) const {
  const std::vector<double>& offset = intervals_[static_cast<std::size_t>(i)].offset;
  const int m =
      static_cast<int>(std::upper_bound(offset.begin(), offset.end(), u) - offset.begin()) - 1;
  return std::clamp(m, 0, static_cast<int>(offset.size()) - 1);
}

bool SlicedIntervalMaps::make(const SlicedModalPropagator& exact, int i) {
  Interval& v = intervals_[static_cast<std::size_t>(i)];
  v.ready = true;
  v.usable = false;
  const double q0 = static_cast<double>(i) / intervals();
  const int pieces = static_cast<int>(v.slice.size());
  // Heads forwards: start -> boundary m + 1 is piece m after start -> boundary m. Each piece's own
  // map is kept in tail[m] for the backward pass.
  v.head[0] = AffineMap{};
  for (int m = 0; m < pieces; ++m) {
    const double h =
        (v.offset[static_cast<std::size_t>(m) + 1] - v.offset[static_cast<std::size_t>(m)]) / f_;
    AffineMap& piece = v.tail[static_cast<std::size_t>(m)];
    if (!exact.loadedSliceMap(v.slice[static_cast<std::size_t>(m)],
                              q0 + v.offset[static_cast<std::size_t>(m)], f_, h, piece)) {
      return false;
    }
    piece.after(v.head[static_cast<std::size_t>(m)], v.head[static_cast<std::size_t>(m) + 1]);
  }
  // Tails backwards: boundary m -> end is (boundary m + 1 -> end) after piece m.
  v.tail[static_cast<std::size_t>(pieces)] = AffineMap{};
  for (int m = pieces - 1; m >= 0; --m) {
    v.tail[static_cast<std::size_t>(m) + 1].after(v.tail[static_cast<std::size_t>(m)], piece_);
    v.tail[static_cast<std::size_t>(m)] = piece_;
  }
  ++made_;
  v.usable = true;
  return true;
}

bool SlicedIntervalMaps::toEnd(const SlicedModalPropagator& exact, int i, int m, State6& y,
                               double drive_force) {
  if (!available(exact, i)) return false;
  intervals_[static_cast<std::size_t>(i)].tail[static_cast<std::size_t>(m)].apply(y, drive_force);
  return true;
}

bool SlicedIntervalMaps::fromStart(const SlicedModalPropagator& exact, int i, int m, State6& y,
                                   double drive_force) {
  if (!available(exact, i)) return false;
  intervals_[static_cast<std::size_t>(i)].head[static_cast<std::size_t>(m)].apply(y, drive_force);
  return true;
}

}  // namespace drivetrain_stiffness
