#pragma once
// Whether an image file's pixels decode, not only its header and metadata: a JPEG cut short
// inside its image data keeps all its EXIF and XMP, so a photo is checked here before any tool
// is told to use it. The same decoder, at a reduced size, draws a photo's picture for an overview.

#include <opencv2/core.hpp>

#include <optional>
#include <string>

namespace shutterlab {

// Decodes the whole of the image data and returns the decoder's first complaint, "" when it
// decodes cleanly. A JPEG is decoded by libjpeg at 1/8 size (its DCT scaling: every coded bit is
// read, little is transformed; 6 and 18 ms for the shared data's 2560 x 1440 SIYI and 2400 x 1800
// DJI photos, 0.37 and 0.59 of OpenImageIO's full decode), and a warning that the coded data is cut
// or damaged counts ("Premature end of JPEG file", "Corrupt JPEG data: bad Huffman code"); one
// libjpeg cannot decode at all, and another format, is decoded whole through OpenImageIO. Never
// throws: a file that cannot be opened is a complaint, a decoder that cannot run is none.
std::string ImageDataProblem(const std::string& path);

// A JPEG's pixels at the smallest of libjpeg's DCT scales (1/8, 1/4, 1/2, whole) that keeps at
// least min_width columns: grey (CV_8UC1) or R, G, B (CV_8UC3), each pixel from its block's
// lowest frequencies (libjpeg's scaled inverse DCT; at 1/8 the block's mean). A 12 MP photo's
// 500-pixel picture costs little more than the entropy decode: 38 against 76 ms whole for a survey
// photo, and no resize of 12 MP after it (a progressive JPEG gains less: its scans are all
// decoded). min_width below 1 counts as 1. nullopt for a file that is not a JPEG or that libjpeg
// cannot decode (CMYK, 12-bit, damaged past its warnings); a damaged one that decodes is drawn as
// it decodes.
std::optional<cv::Mat> ReadJpegScaled(const std::string& path, int min_width);

// What a photo whose pixels do not decode is told: "its image data does not decode (PROBLEM): a
// cut or damaged file; copy it from the card again".
std::string UndecodableImageText(const std::string& problem);

}  // namespace shutterlab
