#include "acquisition/cameras/genicam_glib.h"

namespace bosfuse::acquisition::genicam_detail {

std::string genicam_take(GError*& error) {
  if (error == nullptr) return {};
  std::string message = error->message != nullptr ? error->message : "unknown Aravis error";
  g_clear_error(&error);
  return message;
}

void genicam_check(GError*& error, const std::string& what) {
  if (error != nullptr) throw DeviceError(what + ": " + genicam_take(error));
}

bool genicam_has_feature(ArvDevice* device, const char* name) {
  ArvGcNode* node = arv_device_get_feature(device, name);
  if (node == nullptr) return false;
  if (!ARV_IS_GC_FEATURE_NODE(node)) return true;
  GError* error = nullptr;
  const bool implemented = arv_gc_feature_node_is_implemented(ARV_GC_FEATURE_NODE(node), &error);
  return error == nullptr ? implemented : (genicam_take(error), false);
}

const char* genicam_first_feature(ArvDevice* device, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    if (genicam_has_feature(device, name)) return name;
  }
  return nullptr;
}

std::vector<std::string> genicam_enumeration(ArvDevice* device, const char* feature) {
  guint n = 0;
  GError* error = nullptr;
  const char** values = arv_device_dup_available_enumeration_feature_values_as_strings(device, feature, &n, &error);
  std::vector<std::string> out;
  for (guint i = 0; values != nullptr && i < n; ++i) out.emplace_back(values[i]);
  g_free(values);
  genicam_check(error, std::string("reading the entries of ") + feature);
  return out;
}

GObjectPtr<ArvCamera> genicam_open(const std::string& name) {
  GError* error = nullptr;
  GObjectPtr<ArvCamera> camera(arv_camera_new(name.c_str(), &error));
  genicam_check(error, "cannot open GenICam camera " + name);
  if (!camera) throw DeviceError("cannot open GenICam camera " + name + ": not found");
  return camera;
}

}  // namespace bosfuse::acquisition::genicam_detail
