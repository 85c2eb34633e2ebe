#include "io/exiv2_setup.h"

// exiv2 0.27's headers use std::auto_ptr, deprecated in C++11 and still in libstdc++'s C++17.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>
#pragma GCC diagnostic pop

#include <mutex>

namespace shutterlab::internal {
namespace {

// The XMP toolkit's lock, as exiv2's xmp_exiv2.hpp shows.
void LockXmp(void* mutex, bool lock) {
  if (lock) {
    static_cast<std::mutex*>(mutex)->lock();
  } else {
    static_cast<std::mutex*>(mutex)->unlock();
  }
}

}  // namespace

void InitialiseExiv2() {
  static std::once_flag once;
  static std::mutex xmp_mutex;
  std::call_once(once, [] {
    Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute);
    Exiv2::XmpParser::initialize(LockXmp, &xmp_mutex);
    Exiv2::XmpProperties::registerNs("https://shutterlab.invalid/ns/1.0/", "shutterlab");
    // DJI's flight state, which `survey` writes as a DJI drone does (readers find it under any
    // prefix: io/photo_metadata.h).
    Exiv2::XmpProperties::registerNs("http://www.dji.com/drone-dji/1.0/", "drone-dji");
  });
}

}  // namespace shutterlab::internal
