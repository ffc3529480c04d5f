// SPDX-License-Identifier: Apache-2.0
#pragma once
// Taking samples from a Cyclone reader, shared by the bridge's readers and the sensor inputs
// (private to swivel_dds). Not real-time safe.

#include <dds/dds.h>

#include <array>
#include <cstdint>

namespace swivel::dds {

inline constexpr std::uint32_t kTakeBatch = 16;

/// Takes every available sample of `reader` and calls `fn(sample)` for the valid ones.
template <typename Sample, typename Fn>
void take_all(dds_entity_t reader, Fn&& fn) {
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples[0] = nullptr;  // ask Cyclone to loan the samples
    const dds_return_t n = dds_take(reader, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n <= 0) return;
    for (dds_return_t i = 0; i < n; ++i) {
      if (infos[i].valid_data) fn(*static_cast<const Sample*>(samples[i]));
    }
    dds_return_loan(reader, samples.data(), n);
    if (n < static_cast<dds_return_t>(kTakeBatch)) return;
  }
}

}  // namespace swivel::dds
