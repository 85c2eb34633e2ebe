#include "estimate/batch/item_record.h"

#include "sim/check.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <map>
#include <memory>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

namespace shutterlab {

std::string FileXxh3(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw IoError(IoMessage(path, 0, std::string("cannot read: ") + std::strerror(errno)));
  std::unique_ptr<XXH3_state_t, decltype(&XXH3_freeState)> state(XXH3_createState(),
                                                                 &XXH3_freeState);
  XXH3_64bits_reset(state.get());
  std::vector<char> buffer(1 << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(fd);
      throw IoError(IoMessage(path, 0, std::string("cannot read: ") + std::strerror(error)));
    }
    XXH3_64bits_update(state.get(), buffer.data(), static_cast<size_t>(n));
  }
  ::close(fd);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx",
                static_cast<unsigned long long>(XXH3_64bits_digest(state.get())));
  return hex;
}

std::vector<InputFileStamp> StampInputFiles(const std::vector<std::string>& files,
                                            const std::vector<InputFileStamp>& previous) {
  std::map<std::string, const InputFileStamp*> known;
  for (const InputFileStamp& stamp : previous) known[stamp.path] = &stamp;
  std::vector<InputFileStamp> stamps;
  for (const std::string& path : files) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0)
      throw IoError(IoMessage(path, 0, std::string("cannot read: ") + std::strerror(errno)));
    InputFileStamp stamp;
    stamp.path = path;
    stamp.bytes = static_cast<uint64_t>(st.st_size);
    stamp.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
    const auto at = known.find(path);
    if (at != known.end() && at->second->bytes == stamp.bytes &&
        at->second->mtime_ns == stamp.mtime_ns && !at->second->xxh3.empty()) {
      stamp.xxh3 = at->second->xxh3;
    } else {
      stamp.xxh3 = FileXxh3(path);
    }
    stamps.push_back(std::move(stamp));
  }
  return stamps;
}

nlohmann::json BatchItemRecipe(const std::vector<PlannedCommand>& plan, const std::string& tool) {
  nlohmann::json commands = nlohmann::json::array();
  for (const PlannedCommand& command : plan) commands.push_back(command.args);
  return {{"tool", tool}, {"commands", commands}};
}

nlohmann::json InputStampsJson(const std::vector<InputFileStamp>& stamps) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const InputFileStamp& s : stamps) {
    inputs.push_back(
        {{"path", s.path}, {"bytes", s.bytes}, {"mtime_ns", s.mtime_ns}, {"xxh3", s.xxh3}});
  }
  return inputs;
}

std::vector<InputFileStamp> InputStampsFromRecord(const nlohmann::json& record) {
  std::vector<InputFileStamp> stamps;
  if (!record.is_object() || !record.contains("inputs") || !record["inputs"].is_array())
    return stamps;
  for (const nlohmann::json& input : record["inputs"]) {
    if (!input.is_object()) return {};
    InputFileStamp s;
    s.path = input.value("path", "");
    s.bytes = input.value("bytes", uint64_t{0});
    s.mtime_ns = input.value("mtime_ns", int64_t{0});
    s.xxh3 = input.value("xxh3", "");
    stamps.push_back(std::move(s));
  }
  return stamps;
}

std::string BatchItemStaleReason(const nlohmann::json& record, const nlohmann::json& recipe,
                                 const std::vector<InputFileStamp>& inputs) {
  if (!record.is_object() || !record.contains("status")) return "not made yet";
  if (record["status"] != "done") return "it failed before";
  if (record.value("recipe", nlohmann::json()) != recipe) {
    return record["recipe"].value("tool", "") != recipe["tool"] ? "the tool changed"
                                                                : "its options changed";
  }
  const std::vector<InputFileStamp> before = InputStampsFromRecord(record);
  std::map<std::string, std::string> hash_before;
  for (const InputFileStamp& s : before) hash_before[s.path] = s.xxh3;
  for (const InputFileStamp& s : inputs) {
    const auto at = hash_before.find(s.path);
    if (at == hash_before.end()) return "an input was added: " + s.path;
    if (at->second != s.xxh3) return "an input changed: " + s.path;
    hash_before.erase(at);
  }
  if (!hash_before.empty()) return "an input was removed: " + hash_before.begin()->first;
  return "";
}

}  // namespace shutterlab
