// Mean and standard error of images estimated in independent batches (the standard errors every derivative
// test and the --stderr outputs rely on).
#pragma once
#include "core/image.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace penumbra {

class ImageBatches {
public:
    void add(const Image& image) {
        if (sum_.empty()) {
            width_ = image.width;
            height_ = image.height;
            sum_.assign(image.pixels.size(), Vec3d(0.0));
            sum2_.assign(image.pixels.size(), Vec3d(0.0));
        }
        double mean = 0;
        for (size_t i = 0; i < image.pixels.size(); ++i) {
            const Vec3d v(image.pixels[i]);
            sum_[i] += v;
            sum2_[i] += v * v;
            mean += v.x + v.y + v.z;
        }
        mean /= 3.0 * double(image.pixels.size());
        mean_sum_ += mean;
        mean_sum2_ += mean * mean;
        ++count_;
    }
    int count() const { return count_; }
    Image mean() const {
        Image m(width_, height_);
        for (size_t i = 0; i < sum_.size(); ++i) m.pixels[i] = Color3f(sum_[i] / double(count_));
        return m;
    }
    // Standard error of the mean per pixel and channel (unbiased sample variance / count); empty below 2 batches.
    Image standard_error() const {
        if (count_ < 2) return Image();
        Image s(width_, height_);
        const double n = count_;
        for (size_t i = 0; i < sum_.size(); ++i) {
            const Vec3d m = sum_[i] / n;
            const Vec3d var = (sum2_[i] / n - m * m) * (n / (n - 1.0));
            s.pixels[i] = Color3f(float(std::sqrt(std::max(0.0, var.x) / n)), float(std::sqrt(std::max(0.0, var.y) / n)),
                                  float(std::sqrt(std::max(0.0, var.z) / n)));
        }
        return s;
    }

    // Standard error of the image mean (over pixels and channels) from the spread of the batches' means: unlike
    // sqrt(Σσ²)/N it holds when pixel errors correlate (samples shared by pixels, e.g. photons). 0 below 2.
    double mean_standard_error() const {
        if (count_ < 2) return 0.0;
        const double n = count_, m = mean_sum_ / n;
        return std::sqrt(std::max(0.0, (mean_sum2_ / n - m * m) * (n / (n - 1.0))) / n);
    }

private:
    int width_ = 0, height_ = 0, count_ = 0;
    std::vector<Vec3d> sum_, sum2_;
    double mean_sum_ = 0, mean_sum2_ = 0;
};

} // namespace penumbra
