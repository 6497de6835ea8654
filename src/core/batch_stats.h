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
  // The block sizes whose block means are also tracked (block_standard_error).
  static constexpr std::array<int, 2> Blocks{2, 4};

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
      for (size_t b = 0; b < Blocks.size(); ++b) {
          const std::vector<Vec3d> blocks = block_means(image, Blocks[b]);
          if (block_sum_[b].empty()) {
              block_sum_[b].assign(blocks.size(), Vec3d(0.0));
              block_sum2_[b].assign(blocks.size(), Vec3d(0.0));
          }
          for (size_t i = 0; i < blocks.size(); ++i) {
              block_sum_[b][i] += blocks[i];
              block_sum2_[b][i] += blocks[i] * blocks[i];
          }
      }
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
    Image standard_error() const { return standard_error(sum_, sum2_, width_, height_); }
    // Standard error of the means of k × k pixel blocks (k one of Blocks; partial blocks at the right and
    // bottom borders average their pixels), from the spread of the batches' block means: a filter splats a
    // sample over neighbouring pixels, so their errors correlate and the per-pixel errors combined as
    // independent understate a block's error. Empty below 2 batches.
    Image block_standard_error(int k) const {
        for (size_t b = 0; b < Blocks.size(); ++b)
            if (Blocks[b] == k)
                return standard_error(block_sum_[b], block_sum2_[b], (width_ + k - 1) / k,
                                      (height_ + k - 1) / k);
        return Image();
    }

    // Standard error of the image mean (over pixels and channels) from the spread of the batches' means: unlike
    // sqrt(Σσ²)/N it holds when pixel errors correlate (samples shared by pixels, e.g. photons). 0 below 2.
    double mean_standard_error() const {
        if (count_ < 2) return 0.0;
        const double n = count_, m = mean_sum_ / n;
        return std::sqrt(std::max(0.0, (mean_sum2_ / n - m * m) * (n / (n - 1.0))) / n);
    }

private:
  static std::vector<Vec3d> block_means(const Image& image, int k) {
      const int w = (image.width + k - 1) / k, h = (image.height + k - 1) / k;
      std::vector<Vec3d> out(size_t(w) * size_t(h), Vec3d(0.0));
      for (int by = 0; by < h; ++by)
          for (int bx = 0; bx < w; ++bx) {
              Vec3d sum(0.0);
              int count = 0;
              for (int y = by * k; y < std::min(image.height, (by + 1) * k); ++y)
                  for (int x = bx * k; x < std::min(image.width, (bx + 1) * k); ++x, ++count)
                      sum += Vec3d(image.at(x, y));
              out[size_t(by) * size_t(w) + size_t(bx)] = sum / double(count);
          }
      return out;
  }
  Image standard_error(const std::vector<Vec3d>& sum, const std::vector<Vec3d>& sum2, int width,
                       int height) const {
      if (count_ < 2) return Image();
      Image s(width, height);
      const double n = count_;
      for (size_t i = 0; i < sum.size(); ++i) {
          const Vec3d m = sum[i] / n;
          const Vec3d var = (sum2[i] / n - m * m) * (n / (n - 1.0));
          s.pixels[i] =
              Color3f(float(std::sqrt(std::max(0.0, var.x) / n)), float(std::sqrt(std::max(0.0, var.y) / n)),
                      float(std::sqrt(std::max(0.0, var.z) / n)));
      }
      return s;
  }

    int width_ = 0, height_ = 0, count_ = 0;
    std::vector<Vec3d> sum_, sum2_;
    std::array<std::vector<Vec3d>, Blocks.size()> block_sum_, block_sum2_;
    double mean_sum_ = 0, mean_sum2_ = 0;
};

} // namespace penumbra
