// Fingerprints of packed point sets (see point_sets.hpp).
#include "meshcol/point_sets.hpp"

#include <cstring>

#include "meshcol/batch.hpp"

namespace meshcol {

void point_set_fingerprints(const double* points, const std::int64_t* offsets,
                            std::int64_t sets, int threads, std::uint64_t* out) {
    constexpr std::uint64_t kMix = 0xBF58476D1CE4E5B9ull;
    constexpr std::uint64_t kPlace = 0x94D049BB133111EBull;
    constexpr std::uint64_t kThird = 0xD6E8FEB86659FD93ull;
    parallel_for(sets, resolve_threads(threads, sets, 1024), [&](long long begin, long long end) {
        for (long long s = begin; s < end; ++s) {
            std::uint64_t sum = 0;
            const std::int64_t first = offsets[s];
            for (std::int64_t k = 0; first + k < offsets[s + 1]; ++k) {
                std::uint64_t bits[3];
                std::memcpy(bits, points + 3 * (first + k), sizeof bits);
                std::uint64_t mixed = bits[0] * kMix + bits[1] * kPlace + bits[2] * kThird;
                mixed ^= mixed >> 29;
                sum += mixed * (2 * static_cast<std::uint64_t>(k) + 1);
            }
            out[s] = sum;
        }
    });
}

}  // namespace meshcol
