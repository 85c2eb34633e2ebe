#pragma once
// exiv2 set up once per process for both of its users, photo_metadata (reading photos, from several
// threads) and image_io (copying metadata into written images, with shutterlab's own XMP keys).
// Each used to set it up alone: whichever ran first decided whether XMP had its lock or
// shutterlab's namespace was registered.

namespace shutterlab::internal {

// Mutes exiv2's log (its failures are exceptions, turned into IoError or notes), initialises XMP
// with a lock so that threads may parse it, and registers the XMP namespace of the
// "Xmp.shutterlab.*" keys (https://shutterlab.invalid/ns/1.0/). Idempotent and thread-safe.
void InitialiseExiv2();

}  // namespace shutterlab::internal
