#include "gi/near_field.h"

#include <cmath>

namespace terrain::gi {

void buildNearFieldSteps(std::span<const float> cosSin, int subsample, float cellSize,
                         std::vector<NearFieldStep>& out) {
    const int s = subsample, m = static_cast<int>(cosSin.size() / 2);
    out.assign(static_cast<std::size_t>(m) * s, NearFieldStep{});
    for (int a = 0; a < m; ++a) {
        const double c = cosSin[2 * static_cast<std::size_t>(a)];
        const double sn = cosSin[2 * static_cast<std::size_t>(a) + 1];
        const bool xMajor = std::abs(c) >= std::abs(sn);
        const double major = xMajor ? std::abs(c) : std::abs(sn), minor = xMajor ? sn : c;
        for (int k = 1; k <= s; ++k) {
            const double t = k / major;
            double offset = t * minor;
            if (std::abs(offset - std::round(offset)) < 1e-6) offset = std::round(offset);  // on a texel
            const int i = static_cast<int>(std::floor(offset));
            const double w = offset - i;
            const int along = (xMajor ? c : sn) > 0.0 ? k : -k;
            NearFieldStep& st = out[static_cast<std::size_t>(a) * s + (k - 1)];
            (xMajor ? st.ax : st.ay) = along;
            (xMajor ? st.bx : st.by) = along;
            (xMajor ? st.ay : st.ax) = i;
            (xMajor ? st.by : st.bx) = w > 0.0 ? i + 1 : i;
            st.wA = static_cast<float>(1.0 - w);
            st.wB = static_cast<float>(w);
            st.invTau = static_cast<float>(1.0 / (t * cellSize));
        }
    }
}

}  // namespace terrain::gi
