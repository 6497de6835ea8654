// Spectral data to linear sRGB (Mitsuba 3 `spectrum_list_to_srgb`), .spd reading, named conductor IORs.
#include "core/spectrum.h"

#include "core/error.h"

#include <fstream>
#include <map>
#include <sstream>

namespace penumbra {

namespace {

constexpr double CieMin = 360.0, CieMax = 830.0;
constexpr int CieSamples = 95; // 5 nm spacing
// Scaling that makes a unit spectrum integrate to luminance 1 against the tabulated y-bar (1 / int y-bar).
constexpr double CieYNormalization = 1.0 / 106.7502593994140625;
// Scaling that makes the D65 table below integrate to luminance 1 (together with the y-bar integral above).
constexpr double D65Normalization = 1.0 / 98.99741751876255;

// CIE 1931 2-degree standard observer colour-matching functions x-bar, y-bar, z-bar, 360..830 nm every 5 nm
// (CIE 015:2004, Table T.4; the same tabulation Mitsuba 3 embeds).
const float CieX[CieSamples] = {
    0.0001299f,  0.0002321f,  0.0004149f,  0.0007416f,  0.001368f,   0.002236f,   0.004243f,   0.00765f,
    0.01431f,    0.02319f,    0.04351f,    0.07763f,    0.13438f,    0.21477f,    0.2839f,     0.3285f,
    0.34828f,    0.34806f,    0.3362f,     0.3187f,     0.2908f,     0.2511f,     0.19536f,    0.1421f,
    0.09564f,    0.05795001f, 0.03201f,    0.0147f,     0.0049f,     0.0024f,     0.0093f,     0.0291f,
    0.06327f,    0.1096f,     0.1655f,     0.2257499f,  0.2904f,     0.3597f,     0.4334499f,  0.5120501f,
    0.5945f,     0.6784f,     0.7621f,     0.8425f,     0.9163f,     0.9786f,     1.0263f,     1.0567f,
    1.0622f,     1.0456f,     1.0026f,     0.9384f,     0.8544499f,  0.7514f,     0.6424f,     0.5419f,
    0.4479f,     0.3608f,     0.2835f,     0.2187f,     0.1649f,     0.1212f,     0.0874f,     0.0636f,
    0.04677f,    0.0329f,     0.0227f,     0.01584f,    0.01135916f, 0.008110916f, 0.005790346f, 0.004109457f,
    0.002899327f, 0.00204919f, 0.001439971f, 0.0009999493f, 0.0006900786f, 0.0004760213f, 0.0003323011f,
    0.0002348261f, 0.0001661505f, 0.000117413f, 8.307527e-05f, 5.870652e-05f, 4.150994e-05f, 2.935326e-05f,
    2.067383e-05f, 1.455977e-05f, 1.025398e-05f, 7.221456e-06f, 5.085868e-06f, 3.581652e-06f, 2.522525e-06f,
    1.776509e-06f, 1.251141e-06f};
const float CieY[CieSamples] = {
    3.917e-06f,  6.965e-06f,  1.239e-05f,  2.202e-05f,  3.9e-05f,    6.4e-05f,    0.00012f,    0.000217f,
    0.000396f,   0.00064f,    0.00121f,    0.00218f,    0.004f,      0.0073f,     0.0116f,     0.01684f,
    0.023f,      0.0298f,     0.038f,      0.048f,      0.06f,       0.0739f,     0.09098f,    0.1126f,
    0.13902f,    0.1693f,     0.20802f,    0.2586f,     0.323f,      0.4073f,     0.503f,      0.6082f,
    0.71f,       0.7932f,     0.862f,      0.9148501f,  0.954f,      0.9803f,     0.9949501f,  1.0f,
    0.995f,      0.9786f,     0.952f,      0.9154f,     0.87f,       0.8163f,     0.757f,      0.6949f,
    0.631f,      0.5668f,     0.503f,      0.4412f,     0.381f,      0.321f,      0.265f,      0.217f,
    0.175f,      0.1382f,     0.107f,      0.0816f,     0.061f,      0.04458f,    0.032f,      0.0232f,
    0.017f,      0.01192f,    0.00821f,    0.005723f,   0.004102f,   0.002929f,   0.002091f,   0.001484f,
    0.001047f,   0.00074f,    0.00052f,    0.0003611f,  0.0002492f,  0.0001719f,  0.00012f,    8.48e-05f,
    6e-05f,      4.24e-05f,   3e-05f,      2.12e-05f,   1.499e-05f,  1.06e-05f,   7.4657e-06f, 5.2578e-06f,
    3.7029e-06f, 2.6078e-06f, 1.8366e-06f, 1.2934e-06f, 9.1093e-07f, 6.4153e-07f, 4.5181e-07f};
const float CieZ[CieSamples] = {
    0.0006061f,  0.001086f,   0.001946f,   0.003486f,   0.006450001f, 0.01054999f, 0.02005001f, 0.03621f,
    0.06785001f, 0.1102f,     0.2074f,     0.3713f,     0.6456f,     1.0390501f,  1.3856f,     1.62296f,
    1.74706f,    1.7826f,     1.77211f,    1.7441f,     1.6692f,     1.5281f,     1.28764f,    1.0419f,
    0.8129501f,  0.6162f,     0.46518f,    0.3533f,     0.272f,      0.2123f,     0.1582f,     0.1117f,
    0.07824999f, 0.05725001f, 0.04216f,    0.02984f,    0.0203f,     0.0134f,     0.008749999f, 0.005749999f,
    0.0039f,     0.002749999f, 0.0021f,    0.0018f,     0.001650001f, 0.0014f,    0.0011f,     0.001f,
    0.0008f,     0.0006f,     0.00034f,    0.00024f,    0.00019f,    0.0001f,     4.999999e-05f, 3e-05f,
    2e-05f,      1e-05f,      0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f,
    0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
// CIE standard illuminant D65, relative spectral power (100 at 560 nm), 360..830 nm every 5 nm (CIE 015:2004, Table T.1).
const float D65[CieSamples] = {
    46.6383f, 49.3637f, 52.0891f, 51.0323f, 49.9755f, 52.3118f, 54.6482f, 68.7015f, 82.7549f, 87.1204f,
    91.486f,  92.4589f, 93.4318f, 90.057f,  86.6823f, 95.7736f, 104.865f, 110.936f, 117.008f, 117.41f,
    117.812f, 116.336f, 114.861f, 115.392f, 115.923f, 112.367f, 108.811f, 109.082f, 109.354f, 108.578f,
    107.802f, 106.296f, 104.79f,  106.239f, 107.689f, 106.047f, 104.405f, 104.225f, 104.046f, 102.023f,
    100.0f,   98.1671f, 96.3342f, 96.0611f, 95.788f,  92.2368f, 88.6856f, 89.3459f, 90.0062f, 89.8026f,
    89.5991f, 88.6489f, 87.6987f, 85.4936f, 83.2886f, 83.4939f, 83.6992f, 81.863f,  80.0268f, 80.1207f,
    80.2146f, 81.2462f, 82.2778f, 80.281f,  78.2842f, 74.0027f, 69.7213f, 70.6652f, 71.6091f, 72.979f,
    74.349f,  67.9765f, 61.604f,  65.7448f, 69.8856f, 72.4863f, 75.087f,  69.3398f, 63.5927f, 55.0054f,
    46.4182f, 56.6118f, 66.8054f, 65.0941f, 63.3828f, 63.8434f, 64.304f,  61.8779f, 59.4519f, 55.7054f,
    51.959f,  54.6998f, 57.4406f, 58.8765f, 60.3125f};

// Linear interpolation of a 5 nm table at wavelength w in [360, 830].
double table_lookup(const float* table, double w) {
    const double t = (w - CieMin) * ((CieSamples - 1) / (CieMax - CieMin));
    const int i0 = std::clamp(int(t), 0, CieSamples - 2);
    const double w1 = t - i0;
    return (1.0 - w1) * table[i0] + w1 * table[i0 + 1];
}

} // namespace

// Mitsuba 3 convention: values are scaled by 1 / int(y-bar) (so a unit spectrum has luminance 1), linearly
// interpolated, optionally multiplied by normalized D65, integrated against x-bar, y-bar, z-bar with a
// 1000-point rule over [360, 830] nm (points outside the data's range contribute 0), then converted with
// the Rec. 709 XYZ -> linear sRGB matrix and clamped to [0, 1] (bounded) or to >= 0.
Color3f spectrum_to_rgb(const std::vector<std::pair<float, float>>& samples, bool bounded, bool illuminant) {
    if (samples.empty()) return Color3f(0.f);
    if (samples.size() == 1) return Color3f(samples[0].second);
    double X = 0, Y = 0, Z = 0;
    constexpr int steps = 1000;
    size_t idx = 0;
    for (int i = 0; i < steps; ++i) {
        const double w = CieMin + (i / double(steps - 1)) * (CieMax - CieMin);
        if (w < samples.front().first || w > samples.back().first) continue;
        while (idx + 2 < samples.size() && samples[idx + 1].first <= w) ++idx;
        const double w0 = samples[idx].first, w1 = samples[idx + 1].first;
        const double v0 = samples[idx].second, v1 = samples[idx + 1].second;
        double v = (w1 == w0) ? v0 : ((w1 - w) * v0 + (w - w0) * v1) / (w1 - w0);
        v *= CieYNormalization;
        if (illuminant) v *= table_lookup(D65, w) * D65Normalization;
        X += table_lookup(CieX, w) * v;
        Y += table_lookup(CieY, w) * v;
        Z += table_lookup(CieZ, w) * v;
    }
    const double scale = (CieMax - CieMin) / steps;
    X *= scale, Y *= scale, Z *= scale;
    Color3f rgb(float(3.240479 * X - 1.537150 * Y - 0.498535 * Z), float(-0.969256 * X + 1.875991 * Y + 0.041556 * Z),
                float(0.055648 * X - 0.204043 * Y + 1.057311 * Z));
    rgb = max(rgb, Color3f(0.f));
    if (bounded) rgb = min(rgb, Color3f(1.f));
    return rgb;
}

std::vector<std::pair<float, float>> read_spd(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error(path + ": cannot open spectral data file");
    std::vector<std::pair<float, float>> result;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        const size_t start = line.find_first_not_of(" \t\r");
        if (start == std::string::npos || line[start] == '#') continue;
        std::istringstream iss(line);
        float w, v;
        std::string rest;
        const auto where = [&] { return path + ":" + std::to_string(line_no) + ": "; };
        if (!(iss >> w >> v)) throw Error(where() + "expected \"wavelength value\", got \"" + line + "\"");
        if (iss >> rest) throw Error(where() + "unexpected text \"" + rest + "\" after \"wavelength value\"");
        if (!result.empty() && w <= result.back().first)
            throw Error(where() + "wavelengths must be strictly increasing");
        result.emplace_back(w, v);
    }
    if (result.size() < 2) throw Error(path + ": expected at least two \"wavelength value\" lines");
    return result;
}

// RGB (eta, k) of Mitsuba's named conductors: spectrum_to_rgb(read_spd("<name>.{eta,k}.spd"), unbounded, no D65)
// of the files in mitsuba-data/ior (Mitsuba's ior_from_file in RGB mode). Regenerated and checked against the
// data by the ConductorTableMatchesSpdData test (tests/test_spectrum.cpp), which prints this table on mismatch.
static const std::map<std::string, std::pair<Color3f, Color3f>>& conductor_table() {
    static const std::map<std::string, std::pair<Color3f, Color3f>> table = {
        {"Ag", {{0.155276f, 0.116728f, 0.138388f}, {4.82835f, 3.12222f, 2.1469f}}},
        {"Al", {{1.6575f, 0.880405f, 0.521244f}, {9.22381f, 6.2695f, 4.837f}}},
        {"AlAs", {{3.6053f, 3.23294f, 2.21632f}, {0.000679437f, 0.f, 0.00751271f}}},
        {"AlAs_palik", {{3.6053f, 3.23294f, 2.21632f}, {0.000679437f, 0.f, 0.00751271f}}},
        {"AlSb", {{0.f, 4.13937f, 4.66925f}, {0.f, 0.0940091f, 1.30057f}}},
        {"AlSb_palik", {{0.f, 4.13937f, 4.66925f}, {0.f, 0.0940091f, 1.30057f}}},
        {"Au", {{0.143036f, 0.375307f, 1.44205f}, {3.983f, 2.38556f, 1.60336f}}},
        {"Be", {{4.18501f, 3.18503f, 2.78406f}, {3.83547f, 3.01012f, 2.86899f}}},
        {"Be_palik", {{4.18501f, 3.18503f, 2.78406f}, {3.83547f, 3.01012f, 2.86899f}}},
        {"Cr", {{4.36967f, 2.91651f, 1.6549f}, {5.20655f, 4.23131f, 3.7547f}}},
        {"CsI", {{2.1449f, 1.70232f, 1.66243f}, {0.f, 0.f, 0.f}}},
        {"CsI_palik", {{2.1449f, 1.70232f, 1.66243f}, {0.f, 0.f, 0.f}}},
        {"Cu", {{0.201005f, 0.92375f, 1.10222f}, {3.91326f, 2.45305f, 2.14209f}}},
        {"Cu2O", {{3.55177f, 2.94987f, 2.75188f}, {0.114207f, 0.193897f, 0.606134f}}},
        {"Cu2O_palik", {{3.55177f, 2.94987f, 2.75188f}, {0.114207f, 0.193897f, 0.606134f}}},
        {"CuO", {{3.24754f, 2.4478f, 2.21022f}, {0.52109f, 0.570031f, 0.722179f}}},
        {"CuO_palik", {{3.24754f, 2.4478f, 2.21022f}, {0.52109f, 0.570031f, 0.722179f}}},
        {"Cu_palik", {{0.213229f, 0.919715f, 1.10241f}, {3.92187f, 2.45733f, 2.13658f}}},
        {"Hg", {{2.39894f, 1.44003f, 0.90957f}, {6.32759f, 4.37192f, 3.42176f}}},
        {"HgTe", {{4.77904f, 3.2312f, 2.6599f}, {1.63161f, 1.58081f, 1.72929f}}},
        {"HgTe_palik", {{4.77904f, 3.2312f, 2.6599f}, {1.63161f, 1.58081f, 1.72929f}}},
        {"Hg_palik", {{2.39894f, 1.44003f, 0.90957f}, {6.32759f, 4.37192f, 3.42176f}}},
        {"Ir", {{3.0863f, 2.08219f, 1.61791f}, {5.59215f, 4.06709f, 3.26731f}}},
        {"Ir_palik", {{3.0863f, 2.08219f, 1.61791f}, {5.59215f, 4.06709f, 3.26731f}}},
        {"K", {{0.0640432f, 0.0464098f, 0.0381849f}, {2.1042f, 1.34894f, 0.913126f}}},
        {"K_palik", {{0.0640432f, 0.0464098f, 0.0381849f}, {2.1042f, 1.34894f, 0.913126f}}},
        {"Li", {{0.265791f, 0.195618f, 0.220949f}, {3.54016f, 2.31112f, 1.66861f}}},
        {"Li_palik", {{0.265791f, 0.195618f, 0.220949f}, {3.54016f, 2.31112f, 1.66861f}}},
        {"MgO", {{2.08958f, 1.65072f, 1.59488f}, {4.3327e-12f, 0.f, 2.49865e-11f}}},
        {"MgO_palik", {{2.08958f, 1.65072f, 1.59488f}, {4.3327e-12f, 0.f, 2.49865e-11f}}},
        {"Mo", {{4.48397f, 3.52513f, 2.77631f}, {4.11144f, 3.42083f, 3.15061f}}},
        {"Mo_palik", {{4.48397f, 3.52513f, 2.77631f}, {4.11144f, 3.42083f, 3.15061f}}},
        {"Na_palik", {{0.0602694f, 0.0561409f, 0.0619884f}, {3.17927f, 2.11249f, 1.57904f}}},
        {"Nb", {{3.42007f, 2.79009f, 2.39563f}, {3.44139f, 2.73767f, 2.57975f}}},
        {"Nb_palik", {{3.42007f, 2.79009f, 2.39563f}, {3.44139f, 2.73767f, 2.57975f}}},
        {"Ni_palik", {{2.3673f, 1.66337f, 1.46708f}, {4.49881f, 3.05015f, 2.34544f}}},
        {"Rh", {{2.58579f, 1.86022f, 1.55426f}, {6.78226f, 4.70299f, 3.97607f}}},
        {"Rh_palik", {{2.58579f, 1.86022f, 1.55426f}, {6.78226f, 4.70299f, 3.97607f}}},
        {"Se", {{4.05831f, 2.84294f, 2.82085f}, {0.75405f, 0.638444f, 0.521807f}}},
        {"Se-e", {{5.72285f, 4.16574f, 4.08134f}, {0.871136f, 1.10516f, 1.56532f}}},
        {"Se-e_palik", {{5.72285f, 4.16574f, 4.08134f}, {0.871136f, 1.10516f, 1.56532f}}},
        {"Se_palik", {{4.05831f, 2.84294f, 2.82085f}, {0.75405f, 0.638444f, 0.521807f}}},
        {"SiC", {{3.17234f, 2.52597f, 2.47937f}, {7.53766e-07f, 0.f, 1.01925e-05f}}},
        {"SiC_palik", {{3.17234f, 2.52597f, 2.47937f}, {7.53766e-07f, 0.f, 1.01925e-05f}}},
        {"SnTe", {{4.52425f, 1.98164f, 1.28159f}, {0.f, 0.f, 0.f}}},
        {"SnTe_palik", {{4.52425f, 1.98164f, 1.28159f}, {0.f, 0.f, 0.f}}},
        {"Ta", {{2.06272f, 2.39294f, 2.62793f}, {2.40836f, 1.74149f, 1.94703f}}},
        {"Ta_palik", {{2.06272f, 2.39294f, 2.62793f}, {2.40836f, 1.74149f, 1.94703f}}},
        {"Te", {{7.39023f, 4.4821f, 2.63711f}, {3.25602f, 3.52706f, 3.29205f}}},
        {"Te-e", {{7.50891f, 4.29643f, 2.36999f}, {5.58393f, 4.9472f, 3.99759f}}},
        {"Te-e_palik", {{7.50891f, 4.29643f, 2.36999f}, {5.58393f, 4.9472f, 3.99759f}}},
        {"Te_palik", {{7.39023f, 4.4821f, 2.63711f}, {3.25602f, 3.52706f, 3.29205f}}},
        {"ThF4", {{1.83071f, 1.44223f, 1.38765f}, {0.f, 0.f, 0.f}}},
        {"ThF4_palik", {{1.83071f, 1.44223f, 1.38765f}, {0.f, 0.f, 0.f}}},
        {"TiC", {{3.70053f, 2.83742f, 2.58229f}, {3.26564f, 2.35159f, 2.17279f}}},
        {"TiC_palik", {{3.70053f, 2.83742f, 2.58229f}, {3.26564f, 2.35159f, 2.17279f}}},
        {"TiN", {{1.64845f, 1.15052f, 1.37982f}, {3.36833f, 1.9435f, 1.10207f}}},
        {"TiN_palik", {{1.64845f, 1.15052f, 1.37982f}, {3.36833f, 1.9435f, 1.10207f}}},
        {"TiO2", {{3.45661f, 2.80174f, 2.90517f}, {0.000105265f, 0.f, 0.000652886f}}},
        {"TiO2-e", {{3.10656f, 2.51317f, 2.58244f}, {2.97516e-05f, 0.f, 0.000182698f}}},
        {"TiO2-e_palik", {{3.10656f, 2.51317f, 2.58244f}, {2.97516e-05f, 0.f, 0.000182698f}}},
        {"TiO2_palik", {{3.45661f, 2.80174f, 2.90517f}, {0.000105265f, 0.f, 0.000652886f}}},
        {"VC", {{3.65757f, 2.75274f, 2.53267f}, {3.0683f, 2.19869f, 1.96319f}}},
        {"VC_palik", {{3.65757f, 2.75274f, 2.53267f}, {3.0683f, 2.19869f, 1.96319f}}},
        {"VN", {{2.8656f, 2.11919f, 1.94009f}, {3.03224f, 2.05612f, 1.61631f}}},
        {"VN_palik", {{2.8656f, 2.11919f, 1.94009f}, {3.03224f, 2.05612f, 1.61631f}}},
        {"V_palik", {{4.27758f, 3.51295f, 2.76107f}, {3.4913f, 2.88945f, 3.11152f}}},
        {"W", {{4.37082f, 3.30025f, 2.99841f}, {3.50064f, 2.60487f, 2.27323f}}},
        {"a-C", {{2.94405f, 2.22714f, 1.96816f}, {0.887465f, 0.799299f, 0.81529f}}},
        {"d-C", {{2.70872f, 2.31883f, 2.2289f}, {0.f, 0.f, 0.f}}},
        {"d-C_palik", {{2.70872f, 2.31883f, 2.2289f}, {0.f, 0.f, 0.f}}},
    };
    return table;
}

bool conductor_ior(const std::string& name, Color3f& eta, Color3f& k) {
    const auto& table = conductor_table();
    const auto it = table.find(name);
    if (it == table.end()) return false;
    eta = it->second.first;
    k = it->second.second;
    return true;
}

} // namespace penumbra
