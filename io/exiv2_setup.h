#pragma once
// exiv2 set up once per process for both of its users, photo_metadata (reading photos, from several
// threads) and image_io (copying metadata into written images, with shutterlab's own XMP keys).
// Each used to set it up alone, and XMP is initialised only once: when image_io came first, XMP
// ran without its lock.

namespace shutterlab::internal {

// Mutes exiv2's log (its failures are exceptions, turned into IoError or notes), initialises XMP
// with a lock (exiv2's xmp_exiv2.hpp: it makes the namespace registrations that parsing a photo's
// XMP may do safe from several threads), and registers the XMP namespace of the
// "Xmp.shutterlab.*" keys (https://shutterlab.invalid/ns/1.0/). Idempotent and thread-safe.
void InitialiseExiv2();

}  // namespace shutterlab::internal
