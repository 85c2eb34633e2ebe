#pragma once
// Which way a rolling shutter reads out, and its one spelling in files and messages
// ("top_to_bottom", ...; docs/FORMATS.md camera.json and .gcsv).

#include <optional>
#include <string_view>

namespace shutterlab {

// The rig model (model/camera.h) reads rows: top to bottom or bottom to top. Logs that record a
// direction (Gyroflow's .gcsv frame_readout_direction) may also name the two column orders.
enum class ReadoutDirection { kTopToBottom, kBottomToTop, kLeftToRight, kRightToLeft };

// "top_to_bottom", "bottom_to_top", "left_to_right" or "right_to_left".
inline const char* ReadoutDirectionName(ReadoutDirection direction) {
  switch (direction) {
    case ReadoutDirection::kTopToBottom:
      return "top_to_bottom";
    case ReadoutDirection::kBottomToTop:
      return "bottom_to_top";
    case ReadoutDirection::kLeftToRight:
      return "left_to_right";
    case ReadoutDirection::kRightToLeft:
      return "right_to_left";
  }
  return "top_to_bottom";
}

// The direction a word of ReadoutDirectionName names; nullopt for any other text.
inline std::optional<ReadoutDirection> ParseReadoutDirection(std::string_view word) {
  for (ReadoutDirection d : {ReadoutDirection::kTopToBottom, ReadoutDirection::kBottomToTop,
                             ReadoutDirection::kLeftToRight, ReadoutDirection::kRightToLeft}) {
    if (word == ReadoutDirectionName(d)) return d;
  }
  return std::nullopt;
}

// Gyroflow's names of the same directions (its core's ReadoutDirection, which a .gyroflow project
// writes by name and reads as a name or as its number, 0..3 in this order).
inline const char* GyroflowReadoutDirectionName(ReadoutDirection direction) {
  switch (direction) {
    case ReadoutDirection::kTopToBottom:
      return "TopToBottom";
    case ReadoutDirection::kBottomToTop:
      return "BottomToTop";
    case ReadoutDirection::kLeftToRight:
      return "LeftToRight";
    case ReadoutDirection::kRightToLeft:
      return "RightToLeft";
  }
  return "TopToBottom";
}

// True for the two row orders, the ones a rig model can hold.
inline bool IsRowReadout(ReadoutDirection direction) {
  return direction == ReadoutDirection::kTopToBottom || direction == ReadoutDirection::kBottomToTop;
}

}  // namespace shutterlab
