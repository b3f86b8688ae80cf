#pragma once
// RAII owners and error checks for the Aravis/GLib objects of the GenICam
// source (genicam_source.h) and camera listing (genicam_cameras.h): the
// only headers besides their .cc files that see <arv.h>. Every Aravis
// call that can fail reports through a GError; genicam_check turns one into
// a DeviceError that says what was being done.

#include <arv.h>

#include <memory>
#include <string>
#include <vector>

#include "acquisition/device_reading.h"

namespace bosfuse::acquisition::genicam_detail {

struct GObjectUnref {
  void operator()(void* object) const {
    if (object != nullptr) g_object_unref(object);
  }
};
template <typename T>
using GObjectPtr = std::unique_ptr<T, GObjectUnref>;

// Throws DeviceError("<what>: <GError message>") when `error` is set, and
// frees it. Both leave `error` null, as the next Aravis call needs it.
void genicam_check(GError*& error, const std::string& what);
// The message of `error`, freed; empty when none.
std::string genicam_take(GError*& error);
// A GenICam feature the device has (an implemented node of that name).
bool genicam_has_feature(ArvDevice* device, const char* name);
// The first of `names` the device has; nullptr when none.
const char* genicam_first_feature(ArvDevice* device, std::initializer_list<const char*> names);
// The entries of an enumeration feature (pixel formats, trigger sources).
std::vector<std::string> genicam_enumeration(ArvDevice* device, const char* feature);
// Opens `name` (Aravis id, serial number, physical id or IP address).
GObjectPtr<ArvCamera> genicam_open(const std::string& name);

}  // namespace bosfuse::acquisition::genicam_detail
