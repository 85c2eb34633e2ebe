#include "sim/gyro_source.h"

namespace shutterlab {

GyroTrace ReadAllSamples(GyroSource* source) {
  std::vector<GyroSample> samples;
  for (GyroChunk chunk = source->Next(); !chunk.empty(); chunk = source->Next())
    samples.insert(samples.end(), chunk.begin(), chunk.end());
  return GyroTrace(std::move(samples));
}

}  // namespace shutterlab
