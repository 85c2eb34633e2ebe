#include "render/pictures.h"

#include "sim/check.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace shutterlab {
namespace {

const cv::Scalar kWhite(255, 255, 255);

// Text size that stays readable from a 300 px thumbnail to a 20 MP frame.
double FontScale(int image_height) { return std::clamp(image_height / 700.0, 0.4, 3.0); }

std::string FormatPx(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), value < 10 ? "%.2f px" : "%.1f px", value);
  return text;
}

}  // namespace

cv::Mat ToRgb8(const cv::Mat& image) {
  cv::Mat eight;
  if (image.depth() == CV_8U) {
    eight = image;
  } else if (image.depth() == CV_16U) {
    image.convertTo(eight, CV_8U, 1.0 / 257.0);
  } else {
    image.convertTo(eight, CV_8U);
  }
  cv::Mat rgb;
  if (eight.channels() == 1) {
    cv::cvtColor(eight, rgb, cv::COLOR_GRAY2RGB);
  } else if (eight.channels() == 4) {
    cv::cvtColor(eight, rgb, cv::COLOR_RGBA2RGB);
  } else {
    rgb = eight.clone();
  }
  SHUTTERLAB_CHECK(rgb.type() == CV_8UC3)
      << "cannot show an image with " << image.channels() << " channels";
  return rgb;
}

cv::Mat DisplacementHeatmap(const cv::Mat& displacement, double max_px) {
  SHUTTERLAB_CHECK(displacement.type() == CV_32FC2) << "displacement field must be CV_32FC2";
  cv::Mat magnitude(displacement.size(), CV_32F);
  cv::Mat valid(displacement.size(), CV_8U);
  double field_max = 0.0;
  for (int v = 0; v < displacement.rows; ++v) {
    for (int u = 0; u < displacement.cols; ++u) {
      const cv::Vec2f d = displacement.at<cv::Vec2f>(v, u);
      const float m = std::hypot(d[0], d[1]);
      const bool ok = std::isfinite(m);
      magnitude.at<float>(v, u) = ok ? m : 0.0f;
      valid.at<uchar>(v, u) = ok ? 255 : 0;
      if (ok) field_max = std::max<double>(field_max, m);
    }
  }
  if (max_px <= 0) max_px = field_max > 0 ? field_max : 1.0;
  cv::Mat levels;
  magnitude.convertTo(levels, CV_8U, 255.0 / max_px);
  cv::Mat bgr;
  cv::applyColorMap(levels, bgr, cv::COLORMAP_VIRIDIS);
  bgr.setTo(cv::Scalar::all(0), ~valid);

  // Scale bar: a vertical ramp 0 (bottom) .. max_px (top) with labels, in a strip on the right.
  const int h = displacement.rows;
  const double font = FontScale(h);
  const int bar_width = std::max(12, h / 30), margin = bar_width / 2;
  int baseline = 0;
  const cv::Size label =
      cv::getTextSize(FormatPx(max_px), cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline);
  const int strip_width = margin * 3 + bar_width + label.width;
  // A field too short for the bar's three labels (a thumbnail-sized frame) sits at the top of a
  // taller canvas: the bar's rows would otherwise lie outside it.
  const int canvas_height = std::max(h, 2 * margin + 5 * label.height);
  cv::Mat canvas(canvas_height, displacement.cols + strip_width, CV_8UC3, cv::Scalar::all(32));
  bgr.copyTo(canvas(cv::Rect(0, 0, displacement.cols, h)));
  const int top = label.height + margin, bottom = canvas_height - label.height - margin;
  cv::Mat ramp(std::max(1, bottom - top), 1, CV_8U);
  for (int r = 0; r < ramp.rows; ++r)
    ramp.at<uchar>(r) =
        cv::saturate_cast<uchar>(255.0 * (ramp.rows - 1 - r) / std::max(1, ramp.rows - 1));
  cv::Mat ramp_bgr;
  cv::applyColorMap(ramp, ramp_bgr, cv::COLORMAP_VIRIDIS);
  const int bar_x = displacement.cols + margin;
  cv::resize(ramp_bgr, canvas(cv::Rect(bar_x, top, bar_width, ramp.rows)),
             cv::Size(bar_width, ramp.rows), 0, 0, cv::INTER_NEAREST);
  const int text_x = bar_x + bar_width + margin;
  cv::putText(canvas, FormatPx(max_px), cv::Point(text_x, top + label.height),
              cv::FONT_HERSHEY_SIMPLEX, font, kWhite, 1, cv::LINE_AA);
  cv::putText(canvas, FormatPx(max_px / 2),
              cv::Point(text_x, (top + bottom) / 2 + label.height / 2), cv::FONT_HERSHEY_SIMPLEX,
              font, kWhite, 1, cv::LINE_AA);
  cv::putText(canvas, FormatPx(0), cv::Point(text_x, bottom), cv::FONT_HERSHEY_SIMPLEX, font,
              kWhite, 1, cv::LINE_AA);
  cv::Mat rgb;
  cv::cvtColor(canvas, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& captions) {
  SHUTTERLAB_CHECK(!panels.empty() && panels.size() == captions.size()) << "one caption per panel";
  const int height = panels.front().rows;
  const double font = FontScale(height);
  const int gap = std::max(4, height / 100);
  std::vector<cv::Mat> row;
  for (size_t i = 0; i < panels.size(); ++i) {
    cv::Mat rgb = ToRgb8(panels[i]);
    if (rgb.rows != height) {
      cv::resize(rgb, rgb, cv::Size(std::max(1, rgb.cols * height / rgb.rows), height), 0, 0,
                 cv::INTER_AREA);
    }
    cv::putText(rgb, captions[i], cv::Point(gap * 2, static_cast<int>(30 * font) + gap),
                cv::FONT_HERSHEY_SIMPLEX, font, kWhite, std::max(1, static_cast<int>(font * 2)),
                cv::LINE_AA);
    row.push_back(rgb);
    if (i + 1 < panels.size()) row.emplace_back(height, gap, CV_8UC3, cv::Scalar::all(0));
  }
  cv::Mat out;
  cv::hconcat(row, out);
  return out;
}

cv::Mat ShrinkByWholeFactor(const cv::Mat& image, int min_width) {
  const int k = std::max(1, std::min(image.cols / std::max(1, min_width), image.rows));  // >= 1 row
  if (k == 1) return image;
  cv::Mat small;
  cv::resize(image(cv::Rect(0, 0, image.cols - image.cols % k, image.rows - image.rows % k)), small,
             cv::Size(image.cols / k, image.rows / k), 0, 0, cv::INTER_AREA);
  return small;
}

cv::Mat TiledOverview(const std::vector<cv::Mat>& tiles, const std::vector<std::string>& captions,
                      int tile_width, int columns) {
  SHUTTERLAB_CHECK(!tiles.empty() && tiles.size() == captions.size()) << "one caption per tile";
  SHUTTERLAB_CHECK(tile_width > 0 && columns > 0) << "bad overview layout";
  const int tile_height =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(tile_width) *
                                               tiles.front().rows / tiles.front().cols)));
  const int caption_height = 24;  // a strip under each tile, so captions never cover the picture
  const int cols = std::min<int>(columns, static_cast<int>(tiles.size()));
  const int rows = (static_cast<int>(tiles.size()) + cols - 1) / cols;
  const int gap = 4;
  const int cell_height = tile_height + caption_height;
  cv::Mat canvas((cell_height + gap) * rows - gap, (tile_width + gap) * cols - gap, CV_8UC3,
                 cv::Scalar::all(0));
  for (size_t i = 0; i < tiles.size(); ++i) {
    cv::Mat tile;
    cv::resize(ToRgb8(tiles[i]), tile, cv::Size(tile_width, tile_height), 0, 0, cv::INTER_AREA);
    const int r = static_cast<int>(i) / cols, c = static_cast<int>(i) % cols;
    const int x = c * (tile_width + gap), y = r * (cell_height + gap);
    tile.copyTo(canvas(cv::Rect(x, y, tile_width, tile_height)));
    cv::putText(canvas, captions[i], cv::Point(x + 6, y + tile_height + caption_height - 7),
                cv::FONT_HERSHEY_SIMPLEX, 0.55, kWhite, 1, cv::LINE_AA);
  }
  return canvas;
}

}  // namespace shutterlab
