#pragma once
// Independent readers of the field export for the tests: h5py (Debian
// python3-h5py) lists everything an HDF5 file holds, and Python's
// xml.etree parses the XDMF sidecar and h5py opens every dataset it points
// at. Neither shares code with the writer, so a test that passes on their
// output shows what other programs see. Both run Debian's /usr/bin/python3,
// the interpreter python3-h5py installs into (a `python3` earlier on PATH,
// e.g. from pyenv, may not have it).

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "tests/support/subprocess.h"

namespace bosfuse::report::testreaders {

inline constexpr char kPython[] = "/usr/bin/python3";

// Prints one JSON object: "/path" -> {kind, shape, dtype, attrs, data (small
// datasets, flattened row-major, NaN as null)} for the root, every group and
// dataset, and every soft link ({kind: "softlink", target}).
inline constexpr char kH5pyListing[] = R"PY(
import json, math, sys
import h5py, numpy as np

def plain(v):
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray):
        return [plain(x) for x in v.tolist()]
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v

out = {}
with h5py.File(sys.argv[1], "r") as f:
    def visit(name, link):
        path = "/" + name
        if isinstance(link, h5py.SoftLink):
            out[path] = {"kind": "softlink", "target": link.path}
            return
        obj = f[path]
        entry = {"attrs": {k: plain(v) for k, v in obj.attrs.items()}}
        if isinstance(obj, h5py.Dataset):
            entry.update(kind="dataset", shape=list(obj.shape), dtype=str(obj.dtype),
                         compression=obj.compression, compression_opts=plain(obj.compression_opts),
                         chunks=list(obj.chunks) if obj.chunks else None)
            if obj.size <= 10000:
                entry["data"] = [plain(x) for x in np.asarray(obj[()]).ravel().tolist()]
        else:
            entry["kind"] = "group"
        out[path] = entry
    out["/"] = {"kind": "group", "attrs": {k: plain(v) for k, v in f.attrs.items()}}
    # h5py 3.7 (Debian 12) has no visit_links: walk the groups, seeing links as links.
    def walk(group):
        for key in group:
            name = (group.name.rstrip("/") + "/" + key).lstrip("/")
            link = group.get(key, getlink=True)
            visit(name, link)
            if not isinstance(link, h5py.SoftLink) and isinstance(group[key], h5py.Group):
                walk(group[key])
    walk(f)
print(json.dumps(out))
)PY";

// Prints {"collections": {name: [{name, time, topology, geometry: [{ref, dims,
// shape}], attributes: {name: {ref, dims, type, precision, shape}}}]}} where
// `shape` is what h5py finds at the reference (null: no such dataset). For
// a hyperslab of a dataset, `shape` is the slab's count when it lies inside
// the dataset (null otherwise), with start, stride, count and source_shape.
inline constexpr char kXdmfCheck[] = R"PY(
import json, os, sys
import xml.etree.ElementTree as ET
import h5py

path = sys.argv[1]
root = ET.parse(path).getroot()
assert root.tag == "Xdmf", root.tag
files = {}
def shape_of(ref):
    name, dataset = ref.strip().split(":", 1)
    full = os.path.join(os.path.dirname(path), name)
    if full not in files:
        files[full] = h5py.File(full, "r")
    obj = files[full].get(dataset)
    return list(obj.shape) if isinstance(obj, h5py.Dataset) else None
def item(e):
    if e.get("ItemType") == "HyperSlab":
        # start, stride and count per dimension, then the dataset they select from
        selection, source = e.findall("DataItem")
        numbers = [int(x) for x in selection.text.split()]
        rank = len(numbers) // 3
        start, stride, count = numbers[:rank], numbers[rank:2 * rank], numbers[2 * rank:]
        inner = item(source)
        full = inner["shape"]
        inside = full is not None and len(full) == rank and all(
            s >= 0 and c >= 1 and s + (c - 1) * st < f for s, st, c, f in zip(start, stride, count, full))
        inner.update(dims=e.get("Dimensions"), start=start, stride=stride, count=count, source_shape=full,
                     shape=count if inside else None)
        return inner
    return {"ref": e.text.strip(), "dims": e.get("Dimensions"), "type": e.get("NumberType"),
            "precision": e.get("Precision"), "format": e.get("Format"), "shape": shape_of(e.text)}
out = {"version": root.get("Version"), "collections": {}}
for c in root.find("Domain").findall("Grid"):
    assert c.get("GridType") == "Collection" and c.get("CollectionType") == "Temporal"
    grids = []
    for g in c.findall("Grid"):
        grids.append({"name": g.get("Name"), "time": g.find("Time").get("Value"),
                      "topology": [g.find("Topology").get("TopologyType"), g.find("Topology").get("Dimensions")],
                      "geometry_type": g.find("Geometry").get("GeometryType"),
                      "geometry": [item(e) for e in g.find("Geometry").findall("DataItem")],
                      "attributes": {a.get("Name"): item(a.find("DataItem")) for a in g.findall("Attribute")}})
    out["collections"][c.get("Name")] = grids
print(json.dumps(out))
)PY";

// Single quotes for /bin/sh.
inline std::string sh_quoted(const std::filesystem::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

inline nlohmann::json run_python(const char* script, const std::filesystem::path& argument,
                                 const std::filesystem::path& scratch) {
  const auto script_path = scratch / "reader.py";
  std::ofstream(script_path) << script;
  const auto result =
      testing::run_command(std::string(kPython) + " " + sh_quoted(script_path) + " " + sh_quoted(argument), 60);
  if (result.exit_code != 0) throw std::runtime_error("python reader failed: " + result.output);
  // The JSON is the last line; anything before it (a warning on stderr) is not ours to parse.
  std::string text = result.output;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  return nlohmann::json::parse(text.substr(text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1));
}

// Everything in `h5` as h5py sees it.
inline nlohmann::json h5py_listing(const std::filesystem::path& h5, const std::filesystem::path& scratch) {
  return run_python(kH5pyListing, h5, scratch);
}

// The XDMF sidecar as xml.etree parses it, each reference resolved by h5py.
inline nlohmann::json xdmf_check(const std::filesystem::path& xmf, const std::filesystem::path& scratch) {
  return run_python(kXdmfCheck, xmf, scratch);
}

}  // namespace bosfuse::report::testreaders
