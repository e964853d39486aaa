// The benchmarks' median and quartiles (bench/spread.h).
#include <vector>

#include <doctest/doctest.h>

#include "bench/spread.h"

using terrain::bench::Spread;
using terrain::bench::spreadOf;

TEST_CASE("spread: quartiles between the order statistics, in any input order") {
    // sorted: 1 2 3 4 10; positions 1, 2, 3
    const Spread s = spreadOf({10, 3, 1, 4, 2});
    CHECK(s.median == 3.0);
    CHECK(s.q1 == 2.0);
    CHECK(s.q3 == 4.0);
    CHECK(s.iqr() == 2.0);
    // 4 values: positions 0.75, 1.5, 2.25 between 1 2 4 8
    const Spread e = spreadOf({8, 1, 4, 2});
    CHECK(e.median == doctest::Approx(3.0));
    CHECK(e.q1 == doctest::Approx(1.75));
    CHECK(e.q3 == doctest::Approx(5.0));
}

TEST_CASE("spread: one value has no spread, none gives zeros") {
    const Spread one = spreadOf({7.5});
    CHECK(one.median == 7.5);
    CHECK(one.iqr() == 0.0);
    const Spread none = spreadOf({});
    CHECK(none.median == 0.0);
    CHECK(none.iqr() == 0.0);
}
