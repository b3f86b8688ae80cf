#include "acquisition/cameras/genicam_cameras.h"

#include <algorithm>
#include <utility>

#include "acquisition/cameras/genicam_glib.h"

namespace bosfuse::acquisition {
using namespace genicam_detail;
namespace {

std::string genicam_text(const char* text) { return text != nullptr ? text : ""; }

// Opens the camera to fill in what discovery does not say.
void genicam_describe_opened(const std::string& name, GenicamCameraInfo& info) {
  try {
    GObjectPtr<ArvCamera> camera = genicam_open(name);
    GError* error = nullptr;
    if (info.id.empty()) info.id = genicam_text(arv_camera_get_device_id(camera.get(), &error));
    genicam_take(error);
    if (info.vendor.empty()) info.vendor = genicam_text(arv_camera_get_vendor_name(camera.get(), &error));
    genicam_take(error);
    if (info.model.empty()) info.model = genicam_text(arv_camera_get_model_name(camera.get(), &error));
    genicam_take(error);
    if (info.serial.empty()) info.serial = genicam_text(arv_camera_get_device_serial_number(camera.get(), &error));
    genicam_take(error);
    if (info.protocol.empty()) info.protocol = arv_camera_is_gv_device(camera.get()) ? "GigEVision" : "USB3Vision";
    info.pixel_formats = genicam_enumeration(arv_camera_get_device(camera.get()), "PixelFormat");
  } catch (const DeviceError& e) {
    info.problem = e.what();
  }
}

}  // namespace

std::vector<GenicamCameraInfo> list_genicam_cameras(const std::vector<std::string>& addresses, bool discover) {
  std::vector<GenicamCameraInfo> out;
  if (discover) {
    arv_update_device_list();
    for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
      GenicamCameraInfo info{genicam_text(arv_get_device_id(i)),
                             genicam_text(arv_get_device_vendor(i)),
                             genicam_text(arv_get_device_model(i)),
                             genicam_text(arv_get_device_serial_nbr(i)),
                             genicam_text(arv_get_device_address(i)),
                             genicam_text(arv_get_device_protocol(i)),
                             {},
                             {}};
      if (info.protocol == "Fake") continue;  // Aravis' own in-process test device, not a camera
      genicam_describe_opened(info.id, info);
      out.push_back(std::move(info));
    }
  }
  for (const std::string& address : addresses) {
    const bool known =
        std::any_of(out.begin(), out.end(), [&](const GenicamCameraInfo& c) { return c.address == address; });
    if (known) continue;
    GenicamCameraInfo info;
    info.address = address;
    genicam_describe_opened(address, info);
    out.push_back(std::move(info));
  }
  return out;
}

}  // namespace bosfuse::acquisition
