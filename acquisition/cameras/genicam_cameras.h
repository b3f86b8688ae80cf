#pragma once
// The GenICam cameras Aravis can reach, for `bosfuse cameras`: those its
// discovery finds (GigE Vision broadcast on every interface, USB3 Vision on
// the bus) and those named by address, since discovery by broadcast does
// not reach a camera on loopback or behind a router. Each with the id to
// put in an experiment file's `device`, and the pixel formats it offers.

#include <string>
#include <vector>

namespace bosfuse::acquisition {

struct GenicamCameraInfo {
  std::string id;  // Aravis id, e.g. "Aravis-Fake-BOS01": what `device` takes
  std::string vendor;
  std::string model;
  std::string serial;
  std::string address;   // IP address (GigE Vision) or bus position (USB3 Vision)
  std::string protocol;  // GigEVision, USB3Vision
  std::vector<std::string> pixel_formats;
  std::string problem;  // why it could not be opened to read its formats; empty when it could
};

// Discovered cameras, then each of `addresses` (an IP address or any name
// Aravis opens) not already among them.
std::vector<GenicamCameraInfo> list_genicam_cameras(const std::vector<std::string>& addresses, bool discover = true);

}  // namespace bosfuse::acquisition
