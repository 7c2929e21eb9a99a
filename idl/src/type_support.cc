#include "auv/msg/type_support.h"

#include <fastcdr/exceptions/NotEnoughMemoryException.h>

#include "auv/msg/yaml_convert.h"

namespace auv::msg {

const TypeSupport* findType(const std::string& name) {
  // Accept the DDS name, the ROS-like slash form and the bare struct name.
  std::string scoped = name;
  for (size_t pos; (pos = scoped.find('/')) != std::string::npos;) scoped.replace(pos, 1, "::");
  for (const TypeSupport& ts : allTypes()) {
    if (ts.name == scoped || ts.name == "auv::msg::" + scoped) return &ts;
  }
  return nullptr;
}

namespace detail {

void skipCdr(eprosima::fastcdr::Cdr& cdr, size_t bytes) {
  if (!cdr.jump(bytes)) {
    throw eprosima::fastcdr::exception::NotEnoughMemoryException(
        eprosima::fastcdr::exception::NotEnoughMemoryException::NOT_ENOUGH_MEMORY_MESSAGE_DEFAULT);
  }
}

void checkFields(const YAML::Node& node, const std::string& path,
                 std::initializer_list<const char*> fields) {
  if (node.IsNull()) return;  // `{}` or nothing: every field keeps its default
  if (!node.IsMap()) fail(path, "a map of fields", node);
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    bool known = false;
    for (const char* f : fields) known = known || key == f;
    if (!known) {
      std::string list;
      for (const char* f : fields) list += std::string(list.empty() ? "" : ", ") + f;
      throw std::invalid_argument("unknown field '" + join(path, key) + "' (fields" +
                                  (path.empty() ? "" : " of '" + path + "'") + ": " + list + ")");
    }
  }
}

}  // namespace detail
}  // namespace auv::msg
