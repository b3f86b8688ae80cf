#pragma once
// An emulated USB-HID device for tests of the real hidapi path. umockdev's
// testbed builds a fake sysfs and /dev that libudev and open() see (the test
// binary runs under umockdev-wrapper, which preloads the redirection), and
// replays a scripted conversation on the device node: the test states every
// report the program must write and every reply the device gives. A write
// that does not match the script fails the conversation, so the bytes on the
// wire are checked, not only the decoded values.

#include <umockdev.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace bosfuse::testing {

struct EmulatedHid {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  int interface_number = 0;
  std::string manufacturer;
  std::string product;
  std::string serial;
};

// One step of a scripted conversation: the program writes, or the device replies.
struct ScriptStep {
  enum Kind { kWrite, kReply } kind;
  std::vector<std::uint8_t> bytes;
  int delay_ms = 0;  // before a reply is sent
};

inline ScriptStep expect_write(std::vector<std::uint8_t> bytes) { return {ScriptStep::kWrite, std::move(bytes)}; }
inline ScriptStep reply(std::vector<std::uint8_t> bytes, int delay_ms = 0) {
  return {ScriptStep::kReply, std::move(bytes), delay_ms};
}

// umockdev's script data encoding: bytes below 32 as '^' + (b + 64), '^' as "^`".
inline std::string umockdev_escape(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  for (std::uint8_t b : bytes) {
    if (b < 32) {
      out += '^';
      out += static_cast<char>(b + 64);
    } else if (b == '^') {
      out += "^`";
    } else {
      out += static_cast<char>(b);
    }
  }
  return out;
}

class UmockdevBed {
 public:
  UmockdevBed() : bed_(umockdev_testbed_new()) {}
  ~UmockdevBed() { g_object_unref(bed_); }
  UmockdevBed(const UmockdevBed&) = delete;
  UmockdevBed& operator=(const UmockdevBed&) = delete;

  // Adds a USB device with one HID interface exposed as /dev/hidrawN; returns
  // the sysfs path of its USB device (for remove()).
  std::string add_hid(const EmulatedHid& device, int hidraw_index, int usb_port) {
    const std::string usb = "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-" + std::to_string(usb_port);
    const std::string interface =
        usb + "/1-" + std::to_string(usb_port) + ":1." + std::to_string(device.interface_number);
    const std::string ids = hex(device.vendor_id, 4) + ":" + hex(device.product_id, 4);
    const std::string hid = interface + "/0003:" + upper(ids) + "." + hex(hidraw_index + 1, 4);
    const std::string node = "hidraw" + std::to_string(hidraw_index);
    std::string description =                                                                        //
        "P: " + strip_sys(hid) + "/hidraw/" + node + "\nN: " + node + "\nE: DEVNAME=/dev/" + node +  //
        "\nE: SUBSYSTEM=hidraw\n\n"                                                                  //
        "P: " +
        strip_sys(hid) + "\nE: SUBSYSTEM=hid\nE: DRIVER=hid-generic\nE: HID_ID=0003:0000" +                 //
        upper(hex(device.vendor_id, 4)) + ":0000" + upper(hex(device.product_id, 4)) +                      //
        "\nE: HID_NAME=" + device.manufacturer + " " + device.product + "\nE: HID_UNIQ=" + device.serial +  //
        "\nH: report_descriptor=" + kVendorReportDescriptorHex +
        "\n\n"  //
        "P: " +
        strip_sys(interface) +
        "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_interface\nA: bInterfaceNumber=" + hex(device.interface_number, 2) +
        "\nA: bInterfaceClass=03\n\n";
    // A composite device's interfaces share one USB device, added once.
    if (usb_devices_.insert(usb).second) {
      description += "P: " + strip_sys(usb) +
                     "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nA: idVendor=" + hex(device.vendor_id, 4) +
                     "\nA: idProduct=" + hex(device.product_id, 4) + "\nA: manufacturer=" + device.manufacturer +
                     "\nA: product=" + device.product + "\nA: serial=" + device.serial +
                     "\nA: bcdDevice=0100\nA: busnum=1\nA: devnum=" + std::to_string(usb_port + 1) + "\n";
    }
    GError* error = nullptr;
    if (!umockdev_testbed_add_from_string(bed_, description.c_str(), &error)) fail("add device", error);
    link_hidraw_to_hid(hid, node);
    load_ioctls("/dev/" + node);
    return usb;
  }

  // Adds a raw USB device (usbdevfs node /dev/bus/usb/001/NNN) from its
  // device and configuration descriptors, announcing it with an "add"
  // uevent as the kernel does; returns its sysfs path.
  std::string add_usb(std::uint16_t vendor_id, std::uint16_t product_id, int device_number, int usb_port) {
    const std::string path = "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-" + std::to_string(usb_port);
    char node[32];
    std::snprintf(node, sizeof node, "bus/usb/001/%03d", device_number);
    const std::string description =
        "P: " + strip_sys(path) + "\nN: " + node + "\nE: DEVNAME=/dev/" + node +
        "\nE: DEVTYPE=usb_device\nE: SUBSYSTEM=usb\nE: BUSNUM=001\nE: DEVNUM=" + std::string(node).substr(12) +
        "\nA: busnum=1\nA: devnum=" + std::to_string(device_number) + "\nA: idVendor=" + hex(vendor_id, 4) +
        "\nA: idProduct=" + hex(product_id, 4) +
        "\nA: bConfigurationValue=1\nA: speed=480\nH: descriptors=" + usb_descriptors_hex(vendor_id, product_id) + "\n";
    GError* error = nullptr;
    if (!umockdev_testbed_add_from_string(bed_, description.c_str(), &error)) fail("add device", error);
    umockdev_testbed_uevent(bed_, path.c_str(), "add");
    return path;
  }

  // Unplugs a raw USB device, announcing it with a "remove" uevent.
  void unplug_usb(const std::string& sysfs_path) {
    umockdev_testbed_uevent(bed_, sysfs_path.c_str(), "remove");
    umockdev_testbed_remove_device(bed_, sysfs_path.c_str());
  }

  // Replays `steps` on /dev/hidrawN; when the script ends the device hangs up.
  void script(int hidraw_index, const std::vector<ScriptStep>& steps) {
    std::string text;
    for (const auto& step : steps) {
      text += step.kind == ScriptStep::kWrite ? "w 0 " : "r " + std::to_string(step.delay_ms) + " ";
      text += umockdev_escape(step.bytes) + "\n";
    }
    const std::string device = "/dev/hidraw" + std::to_string(hidraw_index);
    const std::filesystem::path file = write_temp(text, "script");
    GError* error = nullptr;
    if (!umockdev_testbed_load_script(bed_, device.c_str(), file.c_str(), &error)) fail("load script", error);
  }

  // Unplugs the USB device and everything below it.
  // (umockdev keeps the old class links, so a device plugged in again needs
  // a new hidraw index and port, as a real replug often gets.)
  void remove(const std::string& usb_sysfs_path) {
    umockdev_testbed_remove_device(bed_, usb_sysfs_path.c_str());
    usb_devices_.erase(usb_sysfs_path);
  }

 private:
  // A vendor-defined page with 8-byte input and output reports, 25 bytes.
  static constexpr const char* kVendorReportDescriptorHex =
      "0600FF0901A1010901150026FF00750895088102"
      "09019102C0";

  // A device descriptor and one configuration with one vendor interface.
  static std::string usb_descriptors_hex(unsigned vendor_id, unsigned product_id) {
    const std::vector<unsigned> bytes = {18,
                                         1,
                                         0x00,
                                         0x02,
                                         0xFF,
                                         0,
                                         0,
                                         64,
                                         vendor_id & 0xFFu,
                                         vendor_id >> 8u,
                                         product_id & 0xFFu,
                                         product_id >> 8u,
                                         0x00,
                                         0x01,
                                         1,
                                         2,
                                         3,
                                         1,
                                         9,
                                         2,
                                         18,
                                         0,
                                         1,
                                         1,
                                         0,
                                         0x80,
                                         50,  // configuration
                                         9,
                                         4,
                                         0,
                                         0,
                                         0,
                                         0xFF,
                                         0,
                                         0,
                                         0};  // interface 0, vendor class
    std::string text;
    for (unsigned b : bytes) text += hex(b, 2);
    return text;
  }

  static std::string hex(unsigned value, int digits) {
    char text[16];
    std::snprintf(text, sizeof text, "%0*x", digits, value);
    return text;
  }
  static std::string upper(std::string text) {
    for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return text;
  }
  static std::string strip_sys(const std::string& path) { return path.substr(4); }  // "/sys/devices" -> "/devices"

  // The testbed's root folder; umockdev hands out a copy the caller frees.
  std::filesystem::path root_dir() const {
    const std::unique_ptr<gchar, decltype(&g_free)> root(umockdev_testbed_get_root_dir(bed_), g_free);
    return root.get();
  }

  // The kernel links hidrawN/device to its HID parent, and hidapi's filtered
  // enumeration reads the ids through that link; umockdev does not make it.
  void link_hidraw_to_hid(const std::string& hid_sysfs_path, const std::string& node) {
    const std::filesystem::path root = root_dir();
    std::filesystem::create_directory_symlink("../../../" + std::filesystem::path(hid_sysfs_path).filename().string(),
                                              root / (hid_sysfs_path.substr(1) + "/hidraw/" + node + "/device"));
  }

  // hidapi asks the node for its report descriptor size to check it is hidraw.
  void load_ioctls(const std::string& device) {
    const std::filesystem::path file = write_temp("@DEV " + device + "\nHIDIOCGRDESCSIZE 0 19000000\n", "ioctl");
    GError* error = nullptr;
    if (!umockdev_testbed_load_ioctl(bed_, device.c_str(), file.c_str(), &error)) fail("load ioctls", error);
  }

  std::filesystem::path write_temp(const std::string& text, const std::string& suffix) {
    const auto file = root_dir() / ("bosfuse-" + std::to_string(++files_) + "." + suffix);
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

  [[noreturn]] static void fail(const std::string& what, GError* error) {
    const std::string message = what + ": " + (error ? error->message : "unknown umockdev error");
    if (error) g_error_free(error);
    throw std::runtime_error(message);
  }

  UMockdevTestbed* bed_;
  std::set<std::string> usb_devices_;
  int files_ = 0;
};

}  // namespace bosfuse::testing
