// Sampler factory (Mitsuba 3 parameters and defaults). sample_count is rounded as Mitsuba rounds it
// (SamplerSpec::rounded); SamplerDesc::sample_count holds the rounded value.
//
// independent:  sample_count (integer, 4), seed (integer, 0)
// stratified:   sample_count (integer, 4; rounded up to a square), seed (integer, 0), jitter (boolean, true)
// multijitter:  sample_count (integer, 4; rounded up to cols · rows², rows = ⌊∛sample_count⌋), seed (integer,
// 0),
//               jitter (boolean, true)
// orthogonal:   sample_count (integer, 4; rounded up to the square of a prime), strength (integer, 2; only 2,
//               the strength Mitsuba recommends, is supported), seed (integer, 0), jitter (boolean, true)
// ldsampler:    sample_count (integer, 4; rounded up to a power of four, at least 4), seed (integer, 0)
#include "scene/factory.h"
#include "scene/sampler.h"

#include <map>

namespace penumbra {

std::shared_ptr<Object> make_sampler(const Properties& props, const LoadContext&) {
    static const std::map<std::string, SamplerType> types = {{"independent", SamplerType::Independent},
                                                             {"stratified", SamplerType::Stratified},
                                                             {"multijitter", SamplerType::Multijitter},
                                                             {"orthogonal", SamplerType::Orthogonal},
                                                             {"ldsampler", SamplerType::LowDiscrepancy}};
    const auto type = types.find(props.plugin());
    if (type == types.end()) throw_unsupported_plugin(props, ObjectKind::Sampler);
    auto sampler = std::make_shared<SamplerDesc>();
    sampler->type = type->second;
    const int64_t count = props.get_int("sample_count", 4);
    if (count < 1 || count > kMaxSampleCount)
        props.raise("sample_count",
                    "'sample_count' must lie in [1, " + std::to_string(kMaxSampleCount) + "]");
    sampler->sample_count = sampler->rounded(int(count));
    sampler->seed = uint64_t(props.get_int("seed", 0));
    const bool jittered = sampler->type == SamplerType::Stratified ||
                          sampler->type == SamplerType::Multijitter ||
                          sampler->type == SamplerType::Orthogonal;
    if (jittered) sampler->jitter = props.get_bool("jitter", true);
    if (sampler->type == SamplerType::Orthogonal && props.get_int("strength", 2) != 2)
        props.raise("strength",
                    "orthogonal: only 'strength' 2 (orthogonal arrays of strength 2) is supported");
    return sampler;
}

} // namespace penumbra
