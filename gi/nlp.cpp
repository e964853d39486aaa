#include "gi/nlp.h"

#include <cmath>

namespace terrain::gi {

void nlpEvaluate(double z, double out[kNlpCount]) {
    // Legendre P_l by recurrence, then the sqrt((2l+1)/2) normalisation.
    double p[kNlpCount];
    p[0] = 1.0;
    p[1] = z;
    for (int l = 2; l < kNlpCount; ++l) p[l] = ((2.0 * l - 1.0) * z * p[l - 1] - (l - 1.0) * p[l - 2]) / l;
    for (int l = 0; l < kNlpCount; ++l) out[l] = std::sqrt((2.0 * l + 1.0) / 2.0) * p[l];
}

}  // namespace terrain::gi
