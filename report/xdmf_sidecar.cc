#include "report/xdmf_sidecar.h"

#include <fmt/format.h>

#include <fstream>
#include <stdexcept>

#include "report/html.h"

namespace bosfuse::report {
namespace {

std::string data_item(std::string_view h5_name, const std::string& dataset, std::string_view dims, bool uint8) {
  return fmt::format(R"(<DataItem Dimensions="{}" NumberType="{}" Precision="{}" Format="HDF">{}:{}</DataItem>)", dims,
                     uint8 ? "UChar" : "Float", uint8 ? 1 : 8, html_escape(h5_name), html_escape(dataset));
}

// A whole dataset, or XDMF's hyperslab of one: start, stride and count per dimension.
std::string array_item(std::string_view h5_name, const XdmfArray& a, std::size_t rows, std::size_t cols,
                       std::string_view indent) {
  if (!a.frame) return std::string(indent) + data_item(h5_name, a.dataset, fmt::format("{} {}", rows, cols), a.uint8);
  return fmt::format(
      "{0}<DataItem ItemType=\"HyperSlab\" Dimensions=\"1 {1} {2}\" Type=\"HyperSlab\">\n"
      "{0}  <DataItem Dimensions=\"3 3\" Format=\"XML\">{3} 0 0 1 1 1 1 {1} {2}</DataItem>\n"
      "{0}  {4}\n"
      "{0}</DataItem>",
      indent, rows, cols, *a.frame,
      data_item(h5_name, a.dataset, fmt::format("{} {} {}", a.frames, rows, cols), a.uint8));
}

}  // namespace

void write_xdmf(const std::filesystem::path& path, std::string_view h5_name,
                const std::vector<XdmfCollection>& collections) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(fmt::format("cannot write '{}'", path.string()));
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<Xdmf Version=\"3.0\">\n"
      << "  <Domain>\n";
  for (const auto& collection : collections) {
    out << fmt::format("    <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
                       html_escape(collection.name));
    for (const auto& f : collection.frames) {
      const std::string dims = fmt::format("{} {}", f.rows, f.cols);
      // {} prints the shortest text that reads back as the same double: Time equals the t_s stored.
      out << fmt::format("      <Grid Name=\"{}\" GridType=\"Uniform\">\n", html_escape(f.name))
          << fmt::format("        <Time Value=\"{}\"/>\n", f.t_s)
          << fmt::format("        <Topology TopologyType=\"2DRectMesh\" Dimensions=\"{}\"/>\n", dims)
          << "        <Geometry GeometryType=\"VXVY\">\n"
          << "          " << data_item(h5_name, f.x_dataset, std::to_string(f.cols), false) << "\n"
          << "          " << data_item(h5_name, f.y_dataset, std::to_string(f.rows), false) << "\n"
          << "        </Geometry>\n";
      for (const auto& a : f.arrays) {
        out << fmt::format("        <Attribute Name=\"{}\" AttributeType=\"Scalar\" Center=\"Node\">\n",
                           html_escape(a.name))
            << array_item(h5_name, a, f.rows, f.cols, "          ") << "\n"
            << "        </Attribute>\n";
      }
      out << "      </Grid>\n";
    }
    out << "    </Grid>\n";
  }
  out << "  </Domain>\n</Xdmf>\n";
  if (!out.flush()) throw std::runtime_error(fmt::format("cannot write '{}'", path.string()));
}

}  // namespace bosfuse::report
