#pragma once
/// The core's one sort of records by a 64-bit key: least significant digit first, kDigitBits
/// a pass, the digits equal in every key skipped (pair keys (i << 32) | j of a few thousand
/// boxes or faces vary in few of their bits). Stable, so for distinct keys the order is the
/// one any sort gives. No compare of two keys branches, where a comparison sort's branches go
/// either way at random on such keys. Callers sort small inputs with std::sort instead: the
/// passes' fixed cost (2^kDigitBits counts a varying digit) is more than a few dozen keys'
/// sort. Private to the core's sources.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshcol {

/// `items` in increasing order of key(item) (a std::uint64_t).
template <int kDigitBits, class T, class Key>
void lsd_radix_sort(std::vector<T>& items, const Key& key) {
    static_assert(kDigitBits > 0 && kDigitBits <= 16 && 64 % kDigitBits == 0);
    constexpr std::uint64_t kMask = (std::uint64_t{1} << kDigitBits) - 1;
    const size_t n = items.size();
    if (n < 2) return;
    const std::uint64_t first = key(items[0]);
    std::uint64_t varying = 0;
    for (const T& item : items) varying |= key(item) ^ first;
    std::vector<T> other(n);
    std::vector<std::uint32_t> count(size_t{1} << kDigitBits);
    for (int shift = 0; shift < 64; shift += kDigitBits) {
        if (((varying >> shift) & kMask) == 0) continue;
        std::fill(count.begin(), count.end(), 0u);
        for (const T& item : items) ++count[(key(item) >> shift) & kMask];
        std::uint32_t sum = 0;
        for (std::uint32_t& c : count) {
            const std::uint32_t c0 = c;
            c = sum;
            sum += c0;
        }
        for (const T& item : items) other[count[(key(item) >> shift) & kMask]++] = item;
        items.swap(other);
    }
}

}  // namespace meshcol
