// Mean and standard error of images estimated in independent batches (the standard errors every derivative
// test and the --stderr outputs rely on).
#pragma once
#include "core/image.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace penumbra {

class ImageBatches {
public:
  // The block sizes whose block means are also tracked (block_standard_errors).
  static constexpr std::array<int, 2> Blocks{2, 4};

  void add(const Image& image) {
      width_ = image.width;
      height_ = image.height;
      double mean = 0;
      for (const Color3f& v : image.pixels)
          mean += double(v.x) + v.y + v.z;
      mean /= 3.0 * double(image.pixels.size());
      pixels_.add(image);
      for (size_t b = 0; b < Blocks.size(); ++b)
          blocks_[b].add(block_average(image, Blocks[b]));
      mean_sum_ += mean;
      mean_sum2_ += mean * mean;
      ++count_;
  }
    int count() const { return count_; }
    Image mean() const {
        Image m(width_, height_);
        for (size_t i = 0; i < pixels_.sum.size(); ++i)
            m.pixels[i] = Color3f(pixels_.sum[i] / double(count_));
        return m;
    }
    // Standard error of the mean per pixel and channel (unbiased sample variance / count); empty below 2 batches.
    Image standard_error() const { return pixels_.standard_error(count_); }
    // Standard errors of the means of k × k pixel blocks for each k of Blocks (block_average's blocks), from
    // the spread of the batches' block means: a filter splats a sample over neighbouring pixels, so their
    // errors correlate and the per-pixel errors combined as independent understate a block's error. Empty
    // below 2 batches.
    std::array<Image, Blocks.size()> block_standard_errors() const {
        return {blocks_[0].standard_error(count_), blocks_[1].standard_error(count_)};
    }

    // Standard error of the image mean (over pixels and channels) from the spread of the batches' means: unlike
    // sqrt(Σσ²)/N it holds when pixel errors correlate (samples shared by pixels, e.g. photons). 0 below 2.
    double mean_standard_error() const {
        if (count_ < 2) return 0.0;
        const double n = count_, m = mean_sum_ / n;
        return std::sqrt(std::max(0.0, (mean_sum2_ / n - m * m) * (n / (n - 1.0))) / n);
    }

private:
  // Per-pixel sums of an image's values and squares over the batches.
  struct Moments {
      int width = 0, height = 0;
      std::vector<Vec3d> sum, sum2;
      void add(const Image& image) {
          if (sum.empty()) {
              width = image.width;
              height = image.height;
              sum.assign(image.pixels.size(), Vec3d(0.0));
              sum2.assign(image.pixels.size(), Vec3d(0.0));
          }
          for (size_t i = 0; i < image.pixels.size(); ++i) {
              const Vec3d v(image.pixels[i]);
              sum[i] += v;
              sum2[i] += v * v;
          }
      }
      Image standard_error(int count) const {
          if (count < 2) return Image();
          Image s(width, height);
          const double n = count;
          for (size_t i = 0; i < sum.size(); ++i) {
              const Vec3d m = sum[i] / n;
              const Vec3d var = (sum2[i] / n - m * m) * (n / (n - 1.0));
              s.pixels[i] = Color3f(float(std::sqrt(std::max(0.0, var.x) / n)),
                                    float(std::sqrt(std::max(0.0, var.y) / n)),
                                    float(std::sqrt(std::max(0.0, var.z) / n)));
          }
          return s;
      }
  };

    int width_ = 0, height_ = 0, count_ = 0;
    Moments pixels_;
    std::array<Moments, Blocks.size()> blocks_;
    double mean_sum_ = 0, mean_sum2_ = 0;
};

} // namespace penumbra
