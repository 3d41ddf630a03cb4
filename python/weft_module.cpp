// python/weft_module.cpp — the Python module `weft` (issue 9, docs/python.md).
//
// pybind11 bindings of weft_lib for NumPy and Jupyter:
//   FiberBcsdf   the fiber BCSDF (preset or parameter dict): eval, pdf, sample
//   YarnModel    a fitted model.json: the yarn BSDF's eval, pdf, sample, P(T|wi)
//                and the raw network weights
//   gather, fit, render, fit_config, presets, curves_info (`weft curves info`)
// The BSDF calls are vectorised: (n,3) float64 arrays in, one loop in C++ with
// the GIL released, NumPy arrays out. Directions follow the CLI probes exactly
// (docs/cli.md), so that the numbers are the same as `weft fiber eval` and
// `weft yarn eval`: a row of wi or wo must have length 1 within 1e-3 and is
// divided by its length; the wi of sample() and sample_seeded() may be any
// non-zero vector and is normalised as `--wi` is. sample_seeded(wi, count,
// seed) draws exactly the samples of `weft {fiber,yarn} sample`.
// weft::InputError becomes ValueError (its message unchanged), any other C++
// exception RuntimeError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "weft/core/curves.h"
#include "weft/core/error.h"
#include "weft/core/file.h"
#include "weft/core/image.h"
#include "weft/core/image_io.h"
#include "weft/core/json_file.h"
#include "weft/core/json_message.h"
#include "weft/core/limits.h"
#include "weft/core/progress.h"
#include "weft/core/rng.h"
#include "weft/core/text_parse.h"
#include "weft/eval/scene_gen.h"
#include "weft/fiber/fiber_bcsdf.h"
#include "weft/fiber/fiber_params.h"
#include "weft/fit/fit.h"
#include "weft/gather/colour_paths.h"
#include "weft/gather/family.h"
#include "weft/gather/gather.h"
#include "weft/gather/gather_merge.h"
#include "weft/gather/rdm_io.h"
#include "weft/ply/ply.h"
#include "weft/render/curve_report.h"
#include "weft/render/render_merge.h"
#include "weft/render/renderer.h"
#include "weft/render/scene.h"
#include "weft/render/scene_file.h"
#include "weft/view/view_server.h"
#include "weft/yarn/family_model.h"
#include "weft/yarn/material_preset.h"
#include "weft/yarn/yarn_appearance.h"
#include "weft/yarn/yarn_bsdf.h"
#include "weft/yarn/yarn_model.h"

namespace py = pybind11;
using nlohmann::json;

namespace weft::python {

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// ---------------------------------------------------------------------------
// Python objects <-> JSON (parameter, configuration, model and scene dicts).

// Nesting is limited as for JSON text (core/json_file.h), which also stops a
// container that holds itself: it would nest without end.
json jsonFromPy(py::handle h, const std::string& where, int depth = 0) {
    if (h.is_none()) return nullptr;
    const bool container = py::isinstance<py::dict>(h) || py::isinstance<py::list>(h) ||
                           py::isinstance<py::tuple>(h);
    if (container && depth >= kMaxJsonNesting)
        throw InputError(where + ": nested deeper than " + std::to_string(kMaxJsonNesting) +
                         " levels (or a dict or list that contains itself)");
    if (py::isinstance<py::bool_>(h)) return h.cast<bool>();
    if (py::isinstance<py::int_>(h)) {
        try {
            return h.cast<int64_t>();
        } catch (const py::cast_error&) {
            throw InputError(where + ": integer " + py::str(h).cast<std::string>() +
                             " does not fit in 64 bits");
        }
    }
    if (py::isinstance<py::float_>(h)) return h.cast<double>();
    if (py::isinstance<py::str>(h)) return h.cast<std::string>();
    if (py::isinstance<py::dict>(h)) {
        json j = json::object();
        for (const auto& item : h.cast<py::dict>()) {
            if (!py::isinstance<py::str>(item.first))
                throw InputError(where + ": dict keys must be strings, got " +
                                 py::repr(item.first).cast<std::string>());
            const std::string key = item.first.cast<std::string>();
            j[key] = jsonFromPy(item.second, where + "." + key, depth + 1);
        }
        return j;
    }
    if (py::isinstance<py::list>(h) || py::isinstance<py::tuple>(h)) {
        json j = json::array();
        size_t i = 0;
        for (const auto& item : h)
            j.push_back(jsonFromPy(item, where + "[" + std::to_string(i++) + "]", depth + 1));
        return j;
    }
    // NumPy arrays and scalars (np.float32, np.int64, ...) through tolist().
    if (py::hasattr(h, "tolist") && py::hasattr(h, "dtype"))
        return jsonFromPy(h.attr("tolist")(), where, depth);
    throw InputError(where + ": cannot use a value of type " +
                     py::str(py::type::of(h).attr("__name__")).cast<std::string>() +
                     " (expected dict, list, str, number, bool or None)");
}

py::object pyFromJson(const json& j) {
    switch (j.type()) {
        case json::value_t::null:
            return py::none();
        case json::value_t::boolean:
            return py::bool_(j.get<bool>());
        case json::value_t::number_integer:
            return py::int_(j.get<int64_t>());
        case json::value_t::number_unsigned:
            return py::int_(j.get<uint64_t>());
        case json::value_t::number_float:
            return py::float_(j.get<double>());
        case json::value_t::string:
            return py::str(j.get<std::string>());
        case json::value_t::array: {
            py::list list;
            for (const auto& item : j) list.append(pyFromJson(item));
            return list;
        }
        case json::value_t::object: {
            py::dict dict;
            for (const auto& item : j.items()) dict[py::str(item.key())] = pyFromJson(item.value());
            return dict;
        }
        default:
            return py::none();
    }
}

// Runs a reader of user JSON: a type mismatch deep inside it is the user's
// error too, named with `source`.
template <typename F>
auto readUserJson(const std::string& source, F&& read) {
    try {
        return read();
    } catch (const json::exception& e) {
        throw InputError(source + ": " + e.what());
    }
}

// A str or os.PathLike argument as a path string.
std::string pathOf(py::handle h, const std::string& what) {
    if (!py::isinstance<py::str>(h) && !py::hasattr(h, "__fspath__"))
        throw InputError(what + ": expected a path (str or os.PathLike)");
    return py::str(py::module_::import("os").attr("fspath")(h)).cast<std::string>();
}

// ---------------------------------------------------------------------------
// Integer arguments.

// The integer argument `name` within [lo, hi]: a Python int, or any object
// with __index__ (a NumPy integer) other than a bool. Anything else (a value
// out of range however large, a negative one where the range has none, a
// float even when integral, a bool, a string) is an InputError, so ValueError,
// naming the argument and its range: pybind11's own conversion raised
// "RuntimeError: Unable to cast Python instance to C++ type" for 2**40, a
// TypeError for a float, and took True as 1. Every integer argument of the
// module comes through here, before any file is read.
template <typename T>
T integerArg(py::handle h, const std::string& name, T lo, T hi) {
    const auto refused = [&](std::string got) {
        if (got.size() > 80) got = got.substr(0, 77) + "...";
        return InputError(name + ": expected an integer in [" + std::to_string(lo) + ", " +
                          std::to_string(hi) + "], got " + got);
    };
    if (PyBool_Check(h.ptr()) || !PyIndex_Check(h.ptr()))
        throw refused(py::repr(h).cast<std::string>() + " (" +
                      py::str(py::type::of(h).attr("__name__")).cast<std::string>() + ")");
    const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(h.ptr()));
    if (!index) throw py::error_already_set();
    if constexpr (std::is_signed_v<T>) {
        int overflow = 0;
        const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
        if (PyErr_Occurred())
            PyErr_Clear();
        else if (overflow == 0 && v >= lo && v <= hi)
            return static_cast<T>(v);
    } else {
        const unsigned long long v = PyLong_AsUnsignedLongLong(index.ptr());
        if (PyErr_Occurred())
            PyErr_Clear();  // negative, or beyond 64 bits
        else if (v >= lo && v <= hi)
            return static_cast<T>(v);
    }
    throw refused(py::repr(index).cast<std::string>());
}

int intArg(py::handle h, const std::string& name, int lo, int hi) {
    return static_cast<int>(integerArg<int64_t>(h, name, lo, hi));
}

// A seed: any integer in [0, 2^64 - 1], as the CLI's --seed.
uint64_t seedArg(py::handle h, const std::string& name) {
    return integerArg<uint64_t>(h, name, 0, std::numeric_limits<uint64_t>::max());
}

// A sequence of `count` values (a tuple, list or array; not a string), or
// InputError naming `name` and `what` it should hold.
py::sequence sequenceArg(const py::object& h, const std::string& name, size_t count,
                         const std::string& what) {
    if (!py::isinstance<py::sequence>(h) || py::isinstance<py::str>(h) || py::len(h) != count)
        throw InputError(name + ": expected " + what + ", got " + py::repr(h).cast<std::string>());
    return h.cast<py::sequence>();
}

// A colour (r, g, b), each a number in [0, 1]; InputError naming `name`.
Rgb colourArg(const py::object& h, const std::string& name) {
    const std::string what = "(r, g, b) with each value in [0, 1]";
    const py::sequence s = sequenceArg(h, name, 3, what);
    Rgb colour;
    for (int c = 0; c < 3; ++c) {
        const py::object v = s[c];
        const bool number = (py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)) &&
                            !py::isinstance<py::bool_>(v);
        colour[c] = number ? v.cast<double>() : -1.0;
        if (!std::isfinite(colour[c]) || colour[c] < 0 || colour[c] > 1)
            throw InputError(name + ": expected " + what + ", got " +
                             py::repr(h).cast<std::string>());
    }
    return colour;
}

// An sRGB colour: "#rrggbb" or "R,G,B", or (r, g, b) in [0, 1]; InputError naming `name`.
Rgb srgbArg(const py::object& h, const std::string& name) {
    if (py::isinstance<py::str>(h)) return parseSrgbColour(h.cast<std::string>(), name);
    return colourArg(h, name);
}

// ---------------------------------------------------------------------------
// Arrays of directions and random numbers.

// An (n,3) array, or one (3,) vector that broadcasts against the other argument.
struct Rows {
    DoubleArray array;
    const double* data = nullptr;
    size_t n = 0;
    bool single = false;

    Vec3 at(size_t i) const {
        const double* p = data + (single ? 0 : 3 * i);
        return {p[0], p[1], p[2]};
    }
};

Rows rowsOf(const py::handle& h, const char* name) {
    Rows r;
    try {
        r.array = DoubleArray::ensure(h);
    } catch (const py::error_already_set&) {
    }
    if (!r.array)
        throw InputError(std::string(name) + ": expected a float array of shape (n, 3) or (3,)");
    if (r.array.ndim() == 1 && r.array.shape(0) == 3) {
        r.single = true;
        r.n = 1;
    } else if (r.array.ndim() == 2 && r.array.shape(1) == 3) {
        r.n = static_cast<size_t>(r.array.shape(0));
    } else {
        std::ostringstream shape;
        shape << "(";
        for (py::ssize_t d = 0; d < r.array.ndim(); ++d)
            shape << (d ? ", " : "") << r.array.shape(d);
        shape << (r.array.ndim() == 1 ? ",)" : ")");
        throw InputError(std::string(name) + ": expected shape (n, 3) or (3,), got " + shape.str());
    }
    r.data = r.array.data();
    return r;
}

// The number of rows of a result: (3,) vectors broadcast; otherwise the
// row counts must agree.
size_t broadcastRows(const Rows& a, const char* nameA, const Rows& b, const char* nameB) {
    if (a.single) return b.n;
    if (b.single || a.n == b.n) return a.n;
    throw InputError(std::string(nameA) + " has " + std::to_string(a.n) + " rows but " + nameB +
                     " has " + std::to_string(b.n) + " (give equal counts, or one (3,) vector)");
}

// A row of PAIRS in `weft fiber eval`: unit length within 1e-3, renormalised
// (the same arithmetic as the CLI's unitVectorAt, so the results are equal).
Vec3 unitRow(const Rows& r, size_t i, const char* name) {
    const Vec3 v = r.at(i);
    const double len = length(v);
    if (!isFinite(v) || !(std::fabs(len - 1.0) <= 1e-3)) {
        std::ostringstream msg;
        msg << name << " row " << i << ": " << v
            << " is not a unit vector (length must be within 1e-3 of 1)";
        throw InputError(msg.str());
    }
    return v / len;
}

// The incident direction of a sample, normalised as the CLI's --wi.
Vec3 directionRow(const Rows& r, size_t i, const char* name) {
    const Vec3 v = r.at(i);
    const double largest = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    if (!isFinite(v) || !(largest > 0)) {
        std::ostringstream msg;
        msg << name << " row " << i << ": " << v << " must be a finite non-zero vector";
        throw InputError(msg.str());
    }
    return normalizeAnyLength(v);
}

BsdfSampleInput uniformRow(const Rows& r, size_t i) {
    const Vec3 v = r.at(i);
    for (int k = 0; k < 3; ++k) {
        if (!(v[k] >= 0.0 && v[k] < 1.0)) {
            std::ostringstream msg;
            msg << "u row " << i << ": " << v << " must lie in [0, 1)";
            throw InputError(msg.str());
        }
    }
    return {v.x, v.y, v.z};
}

py::array_t<double> rgbArray(size_t n, bool single) {
    if (single) return py::array_t<double>(std::vector<py::ssize_t>{3});
    return py::array_t<double>(std::vector<py::ssize_t>{static_cast<py::ssize_t>(n), 3});
}

// A (n,) array, or a Python float when both inputs were single vectors.
py::object scalarResult(py::array_t<double>& a, bool single) {
    if (single) return py::float_(a.data()[0]);
    return std::move(a);
}

py::array_t<double> scalarArray(size_t n) {
    return py::array_t<double>(std::vector<py::ssize_t>{static_cast<py::ssize_t>(n)});
}

// ---------------------------------------------------------------------------
// The BSDF calls, shared by FiberBcsdf and YarnModel.

template <typename Bsdf>
py::object evalRows(const Bsdf& bsdf, const py::handle& wiArg, const py::handle& woArg) {
    const Rows wi = rowsOf(wiArg, "wi"), wo = rowsOf(woArg, "wo");
    const size_t n = broadcastRows(wi, "wi", wo, "wo");
    const bool single = wi.single && wo.single;
    py::array_t<double> out = rgbArray(n, single);
    double* o = out.mutable_data();
    {
        py::gil_scoped_release release;
        for (size_t i = 0; i < n; ++i) {
            const Vec3 in = unitRow(wi, i, "wi");  // wi checked first
            const Rgb f = bsdf.eval(in, unitRow(wo, i, "wo"));
            o[3 * i] = f.r, o[3 * i + 1] = f.g, o[3 * i + 2] = f.b;
        }
    }
    return out;
}

template <typename Bsdf>
py::object pdfRows(const Bsdf& bsdf, const py::handle& wiArg, const py::handle& woArg) {
    const Rows wi = rowsOf(wiArg, "wi"), wo = rowsOf(woArg, "wo");
    const size_t n = broadcastRows(wi, "wi", wo, "wo");
    py::array_t<double> out = scalarArray(n);
    double* o = out.mutable_data();
    {
        py::gil_scoped_release release;
        for (size_t i = 0; i < n; ++i) {
            const Vec3 in = unitRow(wi, i, "wi");  // wi checked first
            o[i] = bsdf.pdf(in, unitRow(wo, i, "wo"));
        }
    }
    return scalarResult(out, wi.single && wo.single);
}

// {wo, weight, pdf, lobe} of n samples; `draw(i)` returns sample i.
template <typename Draw>
py::dict sampleDict(size_t n, bool single, const Draw& draw) {
    py::array_t<double> wo = rgbArray(n, single), weight = rgbArray(n, single);
    py::array_t<double> pdf = scalarArray(n);
    py::array_t<int64_t> lobe(std::vector<py::ssize_t>{static_cast<py::ssize_t>(n)});
    double *w = wo.mutable_data(), *f = weight.mutable_data(), *p = pdf.mutable_data();
    int64_t* l = lobe.mutable_data();
    {
        py::gil_scoped_release release;
        for (size_t i = 0; i < n; ++i) {
            const BsdfSample s = draw(i);
            w[3 * i] = s.wo.x, w[3 * i + 1] = s.wo.y, w[3 * i + 2] = s.wo.z;
            f[3 * i] = s.weight.r, f[3 * i + 1] = s.weight.g, f[3 * i + 2] = s.weight.b;
            p[i] = s.pdf;
            l[i] = s.lobe;
        }
    }
    py::dict d;
    d["wo"] = wo;
    d["weight"] = weight;
    d["pdf"] = scalarResult(pdf, single);
    if (single)
        d["lobe"] = py::int_(l[0]);
    else
        d["lobe"] = lobe;
    return d;
}

template <typename Bsdf>
py::dict sampleRows(const Bsdf& bsdf, const py::handle& wiArg, const py::handle& uArg) {
    const Rows wi = rowsOf(wiArg, "wi"), u = rowsOf(uArg, "u");
    const size_t n = broadcastRows(wi, "wi", u, "u");
    return sampleDict(n, wi.single && u.single, [&](size_t i) {
        const Vec3 in = directionRow(wi, i, "wi");  // wi checked first
        return bsdf.sample(in, uniformRow(u, i));
    });
}

// The samples of `weft {fiber,yarn} sample --wi WI --count N --seed S`
// (cmd/commands.h, writeSamples): sample i draws from random stream i.
template <typename Bsdf>
py::dict sampleSeeded(const Bsdf& bsdf, const py::handle& wiArg, const py::handle& countArg,
                      const py::handle& seedArgument) {
    const int64_t count = integerArg<int64_t>(countArg, "count", 1, 100000000);
    const uint64_t seed = seedArg(seedArgument, "seed");
    const Rows wiRows = rowsOf(wiArg, "wi");
    if (!wiRows.single)
        throw InputError("wi: sample_seeded takes one incident direction, shape (3,)");
    const Vec3 wi = directionRow(wiRows, 0, "wi");
    return sampleDict(static_cast<size_t>(count), false, [&](size_t i) {
        Rng rng(static_cast<uint64_t>(i), seed);
        const BsdfSampleInput u = {rng.uniform(), rng.uniform(), rng.uniform()};
        return bsdf.sample(wi, u, rng);
    });
}

// ---------------------------------------------------------------------------
// Fiber BCSDF.

FiberParams fiberParamsOf(const py::dict& params) {
    const std::string source = "fiber parameters";
    const json j = jsonFromPy(params, source);
    return readUserJson(source, [&] { return FiberParams::fromJson(j, source); });
}

// ---------------------------------------------------------------------------
// Yarn model: the model (for its weights and JSON) and the BSDF built from it.

struct PyYarnModel {
    YarnModel model;
    std::string source;
    std::unique_ptr<YarnBsdf> bsdf;

    PyYarnModel(YarnModel m, std::string src, bool energyGuard, const std::string& sampling)
        : model(std::move(m)), source(std::move(src)) {
        YarnBsdfOptions options;
        options.energyGuard = energyGuard;
        options.sampling = parseYarnSampling(sampling, "sampling");
        bsdf = std::make_unique<YarnBsdf>(model, source, options);
    }
};

// A float vector as a NumPy array of the given shape (a copy).
py::array_t<float> floatArray(const std::vector<float>& values, std::vector<py::ssize_t> shape) {
    py::array_t<float> a(shape);
    std::copy(values.begin(), values.end(), a.mutable_data());
    return a;
}

// {"layers": [{"weight": (out,in) float32, "bias": (out,), "prelu": (out,) or None}], "output"}
py::dict networkDict(const NetworkWeights& net) {
    py::list layers;
    for (const NetworkLayer& layer : net.layers) {
        py::dict d;
        d["weight"] = floatArray(layer.weight, {layer.out, layer.in});
        d["bias"] = floatArray(layer.bias, {layer.out});
        d["prelu"] = layer.hasPrelu() ? py::object(floatArray(layer.prelu, {layer.out}))
                                      : py::object(py::none());
        layers.append(d);
    }
    py::dict d;
    d["layers"] = layers;
    d["output"] = toString(net.output);
    return d;
}

// ---------------------------------------------------------------------------
// gather, fit, render.

template <typename T>
py::array_t<T> ndarray(const std::vector<T>& values, std::vector<py::ssize_t> shape) {
    py::array_t<T> a(shape);
    std::copy(values.begin(), values.end(), a.mutable_data());
    return a;
}

// The exit-offset histograms' shape (gather.h exitOffsetShape) as NumPy takes it.
std::vector<py::ssize_t> exitOffsetArrayShape() {
    const std::vector<size_t> shape = exitOffsetShape();
    return {shape.begin(), shape.end()};
}

// (k, n) -> shard k of n (core/shard.h).
Shard shardOf(const py::object& shard) {
    const py::sequence kn = sequenceArg(shard, "shard", 2, "a pair (k, n) of integers, 0 <= k < n");
    Shard s;
    s.count = integerArg<int64_t>(kn[1], "shard n", 1, Shard::kMaxCount);
    s.index = integerArg<int64_t>(kn[0], "shard k", 0, s.count - 1);
    return s;
}

py::dict gatherDict(const GatherResult& r, const GatherOptions& o, const std::string& outPath);

// The walk arguments gather() and gather_family() share, into GatherOptions
// or FamilyGatherOptions (the same fields).
template <typename Options>
void walkArgs(Options& o, const py::object& bins, const py::object& maxDepth,
              const py::object& threads, const py::object& segmentsPerTwist,
              const py::object& shard) {
    const py::sequence binCounts =
        sequenceArg(bins, "bins", 4, "four counts (theta_i, phi_i, theta_o, phi_o)");
    int counts[4];
    for (size_t k = 0; k < 4; ++k)
        counts[k] = intArg(binCounts[k], "bins[" + std::to_string(k) + "]", 1, 4096);
    o.bins = {counts[0], counts[1], counts[2], counts[3]};
    o.maxDepth = intArg(maxDepth, "max_depth", 1, 1000000);
    o.threads = intArg(threads, "threads", 0, 1024);
    o.segmentsPerTwist = intArg(segmentsPerTwist, "segments_per_twist", 16, 65536);
    if (!shard.is_none()) o.shard = shardOf(shard);
}

// Progress of a long call with quiet=False, as lines on Python's sys.stderr,
// which Jupyter shows (the process's own stderr, where the CLI writes, it
// does not). Installed while the call runs; the lines come from worker
// threads, which take the GIL to write them (every long call releases it).
std::unique_ptr<ScopedProgressSink> progressToPython(bool quiet) {
    if (quiet) return nullptr;
    return std::make_unique<ScopedProgressSink>([](const std::string& line) {
        py::gil_scoped_acquire gil;
        try {
            py::object err = py::module_::import("sys").attr("stderr");
            err.attr("write")(line);
            err.attr("flush")();
        } catch (const py::error_already_set&) {
            // sys.stderr closed or replaced by something that cannot write: drop the line.
        }
    });
}

py::object pyGatherFamily(const py::object& points, const py::object& paths, const py::object& out,
                          const py::object& box, const py::object& seed, const py::object& bins,
                          const py::object& maxDepth, const py::object& threads,
                          const py::object& segmentsPerTwist, const py::object& shard,
                          const std::string& design, bool quiet) {
    FamilyGatherOptions o;
    o.design = parseFamilyDesign(design, "design");
    o.points = intArg(points, "points", 1, kMaxFamilyPoints);
    o.pathsPerPoint = integerArg<int64_t>(paths, "paths", 1, kMaxPaths);
    o.seed = seedArg(seed, "seed");
    walkArgs(o, bins, maxDepth, threads, segmentsPerTwist, shard);
    // A dict in BOX.json's layout, or the path of one.
    if (py::isinstance<py::dict>(box))
        o.box =
            readUserJson("box", [&] { return FamilyBox::fromJson(jsonFromPy(box, "box"), "box"); });
    else if (!box.is_none())
        o.box = FamilyBox::fromJsonFile(pathOf(box, "box"));
    o.quiet = quiet;
    o.validate();
    const std::string dir = pathOf(out, "out");
    json summary;
    const auto progress = progressToPython(quiet);
    {
        py::gil_scoped_release release;
        summary = familyGatherSummaryJson(o, gatherFamily(o, dir), dir);
    }
    return pyFromJson(summary);
}

// A shard's integer sums (gather_merge.h's part files) and statistics.
py::dict gatherPartDict(const GatherSums& s, const GatherOptions& o, const std::string& outPath) {
    const py::ssize_t ti = s.bins.thetaI, pi = s.bins.phiI, to = s.bins.thetaO, po = s.bins.phiO;
    py::dict d;
    d["count"] = ndarray(s.count, {ti, pi});
    d["count_t"] = ndarray(s.countT, {ti, pi});
    d["sum_r"] = ndarray(s.sumR, {ti, pi, to, po, 3});
    d["sum_m"] = ndarray(s.sumM, {ti, pi, to, po, 3});
    d["sum_truncated"] = ndarray(s.sumTruncated, {ti, pi, 3});
    d["sum_exit_distance"] = ndarray(s.sumExitDistance, {kExitDistanceBins + 1, 3});
    d["sum_exit_offset"] = ndarray(s.sumExitOffset, exitOffsetArrayShape());
    d["sum_m_exit"] = ndarray(s.sumMExit, {ti, pi, to, po, 3});
    d["depth"] = ndarray(s.depth, {static_cast<py::ssize_t>(s.depth.size())});
    json stats = gatherInputs(o, s.fiberRadius, s.period, s.segments);
    stats["shard"] = {{"index", o.shard.index},
                      {"count", o.shard.count},
                      {"first_path", s.firstPath},
                      {"end_path", s.endPath}};
    stats["elapsed_seconds"] = s.seconds;
    stats["rays"] = s.rays;
    stats["out"] = outPath.empty() ? json() : json(outPath);
    d["stats"] = pyFromJson(stats);
    return d;
}

py::dict pyGather(const py::object& preset, const py::object& params, const py::object& fibers,
                  const py::object& density, const py::object& twist, const py::object& paths,
                  const py::object& seed, const py::object& plySeed, const py::object& bins,
                  const py::object& maxDepth, const py::object& threads,
                  const py::object& segmentsPerTwist, const py::object& shard, bool anyColour,
                  const py::object& out, bool quiet) {
    GatherOptions o;
    // The integer arguments first (gather.h and rdm.h give their ranges).
    o.paths = integerArg<int64_t>(paths, "paths", 1, kMaxPaths);
    o.seed = seedArg(seed, "seed");
    if (!plySeed.is_none()) o.plySeed = seedArg(plySeed, "ply_seed");
    walkArgs(o, bins, maxDepth, threads, segmentsPerTwist, shard);
    const int fiberCount = fibers.is_none() ? 0 : intArg(fibers, "fibers", 1, kMaxPlyFibers);
    const bool geometry = !fibers.is_none() || !density.is_none() || !twist.is_none();
    if (!preset.is_none()) {
        if (!params.is_none() || geometry)
            throw InputError(
                "preset gives fiber and ply parameters: do not combine it with "
                "params, fibers, density or twist");
        const MaterialPreset& p = findMaterialPreset(preset.cast<std::string>());
        o.fiber = p.fiber;
        o.ply = p.ply;
        o.material = std::string(p.name);
    } else {
        if (params.is_none() || fibers.is_none() || density.is_none() || twist.is_none())
            throw InputError(
                "give preset=NAME, or params={...} with fibers=N, density=RHO, "
                "twist=ALPHA");
        o.fiber = fiberParamsOf(params.cast<py::dict>());
        o.ply = {fiberCount, density.cast<double>(), twist.cast<double>()};
        o.material = "params (Python)";
    }
    o.quiet = quiet;
    o.anyColour = anyColour;
    o.validate();
    std::unique_ptr<TempDirCommit> dir;
    std::string outPath;
    if (!out.is_none()) {
        outPath = pathOf(out, "out");
        dir = std::make_unique<TempDirCommit>(outPath);  // fails now, not after the walks
    }
    const auto progress = progressToPython(quiet);
    if (!shard.is_none()) {
        // A part: its integer sums (gather_merge.h), written for gather_merge with out=DIR.
        GatherSums sums;
        {
            py::gil_scoped_release release;
            sums = gatherSums(o);
            if (dir) writeGatherPart(sums, o, *dir);
        }
        return gatherPartDict(sums, o, outPath);
    }
    GatherResult r;
    {
        py::gil_scoped_release release;
        r = gatherRdm(o);
        if (dir) writeGather(r, o, *dir);
    }
    return gatherDict(r, o, outPath);
}

py::dict gatherMerge(const std::vector<py::object>& parts, const py::object& out) {
    std::vector<std::string> dirs;
    for (size_t k = 0; k < parts.size(); ++k)
        dirs.push_back(pathOf(parts[k], "parts[" + std::to_string(k) + "]"));
    std::unique_ptr<TempDirCommit> dir;
    std::string outPath;
    if (!out.is_none()) {
        outPath = pathOf(out, "out");
        std::vector<CommandPath> inputs;
        for (const std::string& d : dirs) inputs.push_back({"part", d});
        checkOutputsSpareInputs({}, {}, inputs, {{"out", outPath}});
        dir = std::make_unique<TempDirCommit>(outPath);
    }
    GatherResult r;
    GatherOptions o;
    {
        py::gil_scoped_release release;
        MergedGather m = mergeGatherParts(dirs);
        r = normaliseGather(std::move(m.sums), m.options, m.shards);
        o = m.options;
        if (dir) writeGather(r, o, *dir);
    }
    return gatherDict(r, o, outPath);
}

py::dict gatherRecolour(const py::object& gather, const std::vector<double>& cTT,
                        const py::object& out) {
    const std::string dir = pathOf(gather, "gather");
    if (cTT.size() != 3)
        throw InputError("c_tt: expected three values (r, g, b) in [0, 1], got " +
                         std::to_string(cTT.size()));
    const Rgb colour(cTT[0], cTT[1], cTT[2]);
    std::unique_ptr<TempDirCommit> target;
    std::string outPath;
    if (!out.is_none()) {
        outPath = pathOf(out, "out");
        checkOutputsSpareInputs({}, {}, {{"gather", dir}}, {{"out", outPath}});
        target = std::make_unique<TempDirCommit>(outPath);
    }
    GatherResult r;
    GatherOptions o;
    json source;
    {
        py::gil_scoped_release release;
        RecolouredGather g = recolourGather(dir, colour);
        o = g.options;
        source = {{"recoloured_from",
                   {{"gather", dir},
                    {"c_tt", {g.gatheredCTT.r, g.gatheredCTT.g, g.gatheredCTT.b}}}}};
        r = normaliseGather(std::move(g.sums), o);
        if (target) writeGather(r, o, *target, source);
    }
    py::dict d = gatherDict(r, o, outPath);
    py::dict stats = d["stats"];
    stats["recoloured_from"] = pyFromJson(source.at("recoloured_from"));
    return d;
}

py::dict gatherDict(const GatherResult& r, const GatherOptions& o, const std::string& outPath) {
    const py::ssize_t ti = r.bins.thetaI, pi = r.bins.phiI, to = r.bins.thetaO, po = r.bins.phiO;
    py::dict d;
    d["count"] = ndarray(r.count, {ti, pi});
    d["count_t"] = ndarray(r.countT, {ti, pi});
    d["p_t"] = ndarray(r.pT, {ti, pi});
    d["rdm_r"] = ndarray(r.rdmR, {ti, pi, to, po, 3});
    d["rdm_m"] = ndarray(r.rdmM, {ti, pi, to, po, 3});
    d["truncated"] = ndarray(r.truncated, {ti, pi, 3});
    d["depth"] = ndarray(r.depth, {static_cast<py::ssize_t>(r.depth.size())});
    // None for a recoloured gather (its records do not keep exit points).
    d["exit_distance"] = r.exitDistance.empty()
                             ? py::object(py::none())
                             : py::object(ndarray(r.exitDistance, {kExitDistanceBins + 1, 3}));
    d["exit_offset"] = r.exitOffset.empty()
                           ? py::object(py::none())
                           : py::object(ndarray(r.exitOffset, exitOffsetArrayShape()));
    d["rdm_m_exit"] = r.rdmMExit.empty() ? py::object(py::none())
                                         : py::object(ndarray(r.rdmMExit, {ti, pi, to, po, 3}));
    if (o.anyColour) {
        const ColourPathColumns c = colourPathColumns(r.colourPaths);
        const auto n = static_cast<py::ssize_t>(r.colourPaths.size());
        d["paths_bins"] = ndarray(c.bins, {n, 3});
        d["paths_kind"] = ndarray(c.kinds, {n});
        d["paths_weight"] = ndarray(c.weights, {n, 3});
    }
    // The gather folder's meta.json, and where it was written (None: nowhere).
    json stats = gatherMetadata(r, o);
    stats["out"] = outPath.empty() ? json() : json(outPath);
    d["stats"] = pyFromJson(stats);
    return d;
}

// The CLI's names, plus the model file's spelling "no_r_lobe".
YarnAblation ablationOf(const std::string& name) {
    return parseYarnAblation(name == "no_r_lobe" ? "no-r-lobe" : name, "ablation");
}

FitConfig fitConfigOf(const py::object& config) {
    if (config.is_none()) return FitConfig{};
    if (py::isinstance<py::dict>(config)) {
        const std::string source = "fit config";
        const json j = jsonFromPy(config, source);
        return readUserJson(source, [&] { return FitConfig::fromJson(j, source); });
    }
    const std::string path = pathOf(config, "config");
    return readUserJson(path, [&] { return FitConfig::fromJsonFile(path); });
}

py::dict lossDict(const LossCurve& c) {
    py::dict d;
    d["step"] = ndarray(c.step, {static_cast<py::ssize_t>(c.step.size())});
    d["loss"] = ndarray(c.loss, {static_cast<py::ssize_t>(c.loss.size())});
    return d;
}

py::dict pyFit(const py::object& rdmArg, const py::object& out, const py::object& config,
               const py::object& seedArgument, const py::object& threads,
               const std::string& ablationName, const py::object& reference,
               const py::object& report, const py::object& colourRange,
               const py::object& colourFunctionsArg, bool quiet) {
    const uint64_t seed = seedArg(seedArgument, "seed");
    const std::optional<int> threadCount =
        threads.is_none() ? std::nullopt : std::optional<int>(intArg(threads, "threads", 0, 1024));
    const int colourFunctions =
        intArg(colourFunctionsArg, "colour_functions", 2, ColourBasis::kMaxFunctions);
    FitConfig c = fitConfigOf(config);
    std::unique_ptr<ColourFitOptions> colour;
    if (!colourRange.is_none()) {
        std::pair<double, double> range;
        try {
            range = colourRange.cast<std::pair<double, double>>();
        } catch (const py::cast_error&) {
            throw InputError("colour_range: expected a pair (lo, hi) with 0 < lo < hi <= 1");
        }
        colour = std::make_unique<ColourFitOptions>();
        colour->range = {range.first, range.second};
        colour->range.validate("colour_range");
        colour->functions = colourFunctions;
        if (ablationOf(ablationName) != YarnAblation::None)
            throw InputError("colour_range cannot be combined with an ablation");
    }
    if (threadCount) c.threads = *threadCount;
    if (c.threads < 0 || c.threads > 1024)
        throw InputError("threads = " + std::to_string(c.threads) +
                         " is out of range: allowed [0, 1024]");
    const YarnAblation ablation = ablationOf(ablationName);
    const std::string rdmDir = pathOf(rdmArg, "rdm");
    const std::string outPath = out.is_none() ? std::string() : pathOf(out, "out");
    const std::string reportDir = report.is_none() ? std::string() : pathOf(report, "report");
    const std::string referenceDir =
        reference.is_none() ? std::string() : pathOf(reference, "reference");
    for (const std::string& path : {outPath, reportDir}) {
        const std::filesystem::path parent = std::filesystem::path(path).parent_path();
        std::error_code ec;
        if (!path.empty() && !parent.empty() && !std::filesystem::is_directory(parent, ec))
            throw InputError(path + ": the folder " + parent.string() + " does not exist");
    }
    std::optional<FitResult> result;
    const auto progress = progressToPython(quiet);
    {
        py::gil_scoped_release release;
        const RdmData rdm = loadRdm(rdmDir);
        std::unique_ptr<RdmData> ref;
        if (!referenceDir.empty()) ref = std::make_unique<RdmData>(loadRdm(referenceDir));
        std::vector<ColourPath> colourPaths;
        if (colour) {
            colourPaths = loadColourPaths(rdmDir);
            colour->paths = &colourPaths;
        }
        result = fitYarnModel(rdm, c, seed, quiet, ablation, colour.get());
        if (!outPath.empty()) saveYarnModel(result->model, outPath);
        if (!reportDir.empty()) {
            // Measured against what it was fitted to (fit.h, fitTarget).
            std::unique_ptr<RdmData> refTarget;
            if (ref) refTarget = std::make_unique<RdmData>(fitTarget(*ref, result->model));
            writeFitReport(*result, fitTarget(rdm, result->model), refTarget.get(), reportDir);
        }
    }
    const FitReport& r = result->report;
    const auto finite = [](double v) -> py::object {
        return std::isfinite(v) ? py::object(py::float_(v)) : py::object(py::none());
    };
    py::dict summary;
    summary["t_rmse"] = r.tRmse;
    summary["t_rmse_unweighted"] = r.tRmseUnweighted;
    summary["m_rel_l2"] = r.mRelL2;
    summary["r_rel_l2"] = finite(r.rRelL2);
    summary["r_rel_l2_eq8"] = finite(r.rRelL2Eq8);
    summary["m_second_moment"] = finite(r.mSecondMoment);
    summary["seconds"] = r.seconds;
    summary["m_samples_per_second"] = r.mSamplesPerSecond;
    summary["t_loss"] = lossDict(r.tLoss);
    summary["m_loss"] = lossDict(r.mLoss);
    summary["calibration"] = pyFromJson(r.calibration);
    summary["colour"] = pyFromJson(r.colour);
    summary["out"] = outPath.empty() ? py::object(py::none()) : py::object(py::str(outPath));
    summary["report"] = reportDir.empty() ? py::object(py::none()) : py::object(py::str(reportDir));
    py::dict d;
    d["model"] = py::cast(std::make_unique<PyYarnModel>(
        std::move(result->model), outPath.empty() ? "fitted model" : outPath, true, "tabulated"));
    d["report"] = summary;
    return d;
}

// An (H, W, 3) float32 array of an image.
py::array_t<float> imageArray(const Image& image) {
    py::array_t<float> pixels(std::vector<py::ssize_t>{image.height, image.width, 3});
    std::copy(image.pixels.begin(), image.pixels.end(), pixels.mutable_data());
    return pixels;
}

// weft.save_image: .exr (linear float) or .png (8-bit sRGB after 2^exposure,
// clamped; exposure a number of stops or "auto", core/image.h autoExposure).
py::object pySaveImage(const py::object& pathArg, const py::object& imageArg,
                       const py::object& exposureArg) {
    const std::string path = pathOf(pathArg, "path");
    const std::string ext = lowercaseExtension(path);
    if (ext != ".exr" && ext != ".png")
        throw InputError("path " + path + ": expected .exr (linear) or .png (tone-mapped)");
    const auto array =
        py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(imageArg);
    if (!array || array.ndim() != 3 || array.shape(2) != 3 || array.shape(0) < 1 ||
        array.shape(1) < 1 || array.shape(0) > 16384 || array.shape(1) > 16384)
        throw InputError("image: expected an (H, W, 3) array of floats, H and W in [1, 16384]");
    Image image(static_cast<int>(array.shape(1)), static_cast<int>(array.shape(0)));
    std::copy(array.data(), array.data() + image.pixels.size(), image.pixels.begin());
    checkFinitePixels(image, "image");
    double stops = 0;
    bool automatic = false;
    if (py::isinstance<py::str>(exposureArg)) {
        if (exposureArg.cast<std::string>() != "auto")
            throw InputError("exposure: expected stops (a number in [-64, 64]) or \"auto\"");
        automatic = true;
        stops = autoExposure(image);
    } else {
        stops = exposureArg.cast<double>();
        checkExposureStops(stops, "exposure");
    }
    if (ext == ".exr" && (automatic || stops != 0))
        throw InputError("exposure applies to .png: an .exr stays linear");
    {
        py::gil_scoped_release release;
        writeFileAtomic(path, ext == ".exr" ? encodeExr(image, path) : encodePng(image, stops));
    }
    return py::float_(stops);
}

py::array_t<double> pyCurvesPoints(const py::object& pathArg) {
    const std::string path = pathOf(pathArg, "path");
    CurveSet set;
    {
        py::gil_scoped_release release;
        set = readCurves(path);
    }
    const std::vector<double> rows = pointRows(set);
    py::array_t<double> points(std::vector<py::ssize_t>{static_cast<py::ssize_t>(set.pointCount()), 4});
    std::copy(rows.begin(), rows.end(), points.mutable_data());
    return points;
}

py::array_t<float> pyReadImage(const py::object& pathArg) {
    const std::string path = pathOf(pathArg, "path");
    Image image;
    {
        py::gil_scoped_release release;
        image = readImageOrPng(path);
    }
    return imageArray(image);
}

// weft.view: a ViewSession and its server, alive while the object is
// (docs/view.md, "From Python"); in a notebook the object shows the page.
class PyView {
  public:
    PyView(const view::ViewOptions& options, const view::ServerOptions& server)
        : session_(std::make_unique<view::ViewSession>(options)),
          server_(std::make_unique<view::ViewServer>(*session_, server)) {}
    ~PyView() { stop(); }
    std::string url() const {
        if (!server_) throw InputError("this view is stopped");
        return server_->url();
    }
    py::object state() const { return pyFromJson(live().state()); }
    py::object stats() const { return pyFromJson(live().stats()); }
    py::object save() { return pyFromJson(live().save()); }
    void stop() {
        py::gil_scoped_release release;
        if (server_) server_->stop();
        if (session_) session_->stop();
        server_.reset();
        session_.reset();
    }
    std::string html() const {
        if (!server_) return "<p>weft view: stopped</p>";
        return "<iframe src=\"" + server_->url() +
               "\" width=\"100%\" height=\"720\" style=\"border:0\"></iframe>";
    }

  private:
    view::ViewSession& live() const {
        if (!session_) throw InputError("this view is stopped");
        return *session_;
    }
    std::unique_ptr<view::ViewSession> session_;
    std::unique_ptr<view::ViewServer> server_;
};

py::tuple pyRender(const py::object& sceneArg, const py::object& modeName, const py::object& spp,
                   const py::object& seconds, const py::object& threads, const py::object& seed,
                   const py::object& fiberSeed, bool nee, const std::string& yarnSampling,
                   const py::object& sampler, const py::object& baseDir, const py::object& shard,
                   bool quiet, const std::string& integrator, const py::object& progressCallback,
                   double progressSeconds) {
    if (!progressCallback.is_none() && !PyCallable_Check(progressCallback.ptr()))
        throw InputError("progress: expected a callable progress(fraction, image) or None");
    // The integer arguments first (renderer.h gives their ranges).
    const std::optional<int> sppCount =
        spp.is_none() ? std::nullopt : std::optional<int>(intArg(spp, "spp", 1, 1 << 20));
    const int threadCount = intArg(threads, "threads", 0, 1024);
    const std::optional<uint64_t> seedValue =
        seed.is_none() ? std::nullopt : std::optional<uint64_t>(seedArg(seed, "seed"));
    const std::optional<uint64_t> fiberSeedValue =
        fiberSeed.is_none() ? std::nullopt
                            : std::optional<uint64_t>(seedArg(fiberSeed, "fiber_seed"));
    const std::optional<Shard> shardValue =
        shard.is_none() ? std::nullopt : std::optional<Shard>(shardOf(shard));
    render::SceneOptions sceneOptions;
    if (!modeName.is_none())
        sceneOptions.mode = render::yarnModeNamed(modeName.cast<std::string>(), "mode").name();
    sceneOptions.quiet = quiet;
    sceneOptions.yarn.sampling = parseYarnSampling(yarnSampling, "yarn_sampling");
    render::SceneDesc desc;
    py::object sceneFile = py::none();
    if (py::isinstance<py::dict>(sceneArg)) {
        const std::string base =
            std::filesystem::absolute(baseDir.is_none()
                                          ? std::filesystem::current_path()
                                          : std::filesystem::path(pathOf(baseDir, "base_dir")))
                .string();
        const json j = jsonFromPy(sceneArg, "scene");
        desc = readUserJson("scene", [&] { return render::parseScene(j, "scene", base); });
    } else {
        if (!baseDir.is_none())
            throw InputError(
                "base_dir applies to a scene dict; a scene file's paths are "
                "relative to its folder");
        const std::string path = pathOf(sceneArg, "scene");
        desc = render::loadScene(path);
        sceneFile = py::str(path);
    }
    // Part of the scene (its hash), as `weft render --fiber-seed`.
    if (fiberSeedValue) desc.render.fiberSeed = *fiberSeedValue;
    render::RenderOptions options;
    options.spp = sppCount ? *sppCount : (!seconds.is_none() ? 0 : desc.render.spp);
    options.seconds = seconds.is_none() ? 0.0 : seconds.cast<double>();
    options.threads = threadCount;
    options.seed = seedValue ? *seedValue : desc.render.seed;
    options.maxDepth = desc.render.maxDepth;
    options.sampler = sampler.is_none()
                          ? desc.render.sampler
                          : render::parseSampler(sampler.cast<std::string>(), "sampler");
    options.nextEventEstimation = nee;
    options.integrator = render::parsePathIntegrator(integrator, "integrator");
    options.quiet = quiet;
    options.shard = shardValue;
    // progress(fraction, image) every progress_seconds (between passes), from this
    // thread (a render engine's progress bar and live image); a False return
    // stops the render, which returns its partial image (stats["partial"]).
    std::atomic<bool> stopAsked{false};
    std::optional<py::error_already_set> callbackError;
    if (!progressCallback.is_none()) {
        if (!(progressSeconds >= 0.1 && progressSeconds <= 1e6))
            throw InputError("progress_seconds = " + formatNumber(progressSeconds) +
                             " is out of range: allowed [0.1, 1e6]");
        options.checkpointSeconds = progressSeconds;
        options.checkpoint = [&](const render::RenderResult& partial) {
            const render::RenderStats& st = partial.stats;
            const double fraction =
                st.sppRequested > 0
                    ? static_cast<double>(st.spp) / static_cast<double>(st.sppRequested)
                    : std::min(1.0, st.seconds / std::max(options.seconds, 1e-9));
            py::gil_scoped_acquire gil;
            try {
                const py::object answer = progressCallback(fraction, imageArray(partial.image));
                if (py::isinstance<py::bool_>(answer) && !answer.cast<bool>()) stopAsked = true;
            } catch (py::error_already_set& e) {
                callbackError = std::move(e);
                stopAsked = true;
            }
        };
        options.stopRequested = [&] { return stopAsked.load(); };
    }
    options.validate();
    std::optional<render::RenderResult> result;
    std::string hash;
    const auto progress = progressToPython(quiet);
    {
        py::gil_scoped_release release;
        hash = render::sceneHash(desc);
        const render::Scene scene(desc, sceneOptions);
        result = render::render(scene, options);
    }
    if (callbackError) throw std::move(*callbackError);
    // The overlap warnings of `weft render`, as Python warnings (filterable).
    for (const std::string& w :
         render::yarnOverlapWarnings(desc.path, result->stats.scene.yarnOverlap))
        if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw py::error_already_set();
    if (const std::string w = render::truncationWarning(result->stats, options.maxDepth);
        !w.empty())
        if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw py::error_already_set();
    json stats = render::toJson(result->stats);
    stats["scene_hash"] = hash;
    stats["next_event_estimation"] = nee;
    stats["yarn_sampling"] = yarnSamplingName(sceneOptions.yarn.sampling);
    stats["max_depth"] = options.maxDepth;
    stats["version"] = WEFT_VERSION;
    py::dict statsDict = pyFromJson(stats).cast<py::dict>();
    statsDict["scene_file"] = sceneFile;
    return py::make_tuple(imageArray(result->image), statsDict);
}

py::tuple renderMerge(const std::vector<py::object>& parts) {
    std::vector<std::string> paths;
    for (size_t k = 0; k < parts.size(); ++k)
        paths.push_back(pathOf(parts[k], "parts[" + std::to_string(k) + "]"));
    std::optional<render::MergedRender> merged;
    {
        py::gil_scoped_release release;
        merged = render::mergeRenderParts(paths);
    }
    return py::make_tuple(imageArray(merged->image), pyFromJson(merged->stats));
}

py::object pyCurvesInfo(const py::object& pathArg, const py::object& radiusArg) {
    const std::string path = pathOf(pathArg, "path");
    std::optional<double> radius;
    if (!radiusArg.is_none()) {
        radius = radiusArg.cast<double>();
        render::checkOverlapRadius(*radius, "radius");
    }
    json report;
    {
        py::gil_scoped_release release;
        report = render::toJson(render::curveReport(readCurves(path), radius));
    }
    report["file"] = path;
    return pyFromJson(report);
}

py::object pyScene(const std::string& kindName, const py::object& model, const py::object& out,
                   const py::object& size, double radius, const py::object& plies, double plyTwist,
                   const py::object& width, const py::object& height, const py::object& spp,
                   const py::object& envmap, const py::object& colours,
                   const py::object& appearances, const py::object& stripe,
                   const py::object& dyeLength, const py::object& yarn, const py::object& curves,
                   const py::object& curveRadius, const std::string& view, bool floor) {
    const eval::SceneKind kind = eval::parseSceneKind(kindName);
    eval::SceneOptions o;
    // The curves kind: a curve file framed whole (docs/scenes.md, "Your own curves").
    if ((kind == eval::SceneKind::Curves) != !curves.is_none())
        throw InputError(kind == eval::SceneKind::Curves
                             ? "curves: the \"curves\" kind needs the curve file (curves=PATH)"
                             : "curves= applies to the \"curves\" kind only");
    if (!curves.is_none()) o.curves = pathOf(curves, "curves");
    if (!curveRadius.is_none()) {
        if (kind != eval::SceneKind::Curves)
            throw InputError("curve_radius applies to the \"curves\" kind only (radius= elsewhere)");
        o.curveRadius = curveRadius.cast<double>();
    }
    o.view = eval::parseCurvesView(view);
    o.floor = floor;
    // A family model's yarn (docs/family.md): a dict as weft yarn at takes.
    if (!yarn.is_none())
        o.yarn = readUserJson(
            "yarn", [&] { return YarnPoint::fromJson(jsonFromPy(yarn, "yarn"), "yarn", ""); });
    // The integer arguments first (eval/scene_gen.h gives their ranges).
    o.size = intArg(size, "size", 1, eval::kMaxPatchSize);
    o.plies = intArg(plies, "plies", 1, 16);
    o.width = intArg(width, "width", 1, 16384);
    o.height = intArg(height, "height", 1, 16384);
    o.spp = intArg(spp, "spp", 1, 1 << 20);
    if (!stripe.is_none()) o.stripe = intArg(stripe, "stripe", 1, eval::kMaxPatchSize);
    o.model = pathOf(model, "model");
    const std::string dir = pathOf(out, "out");
    o.radius = radius;
    o.plyTwist = plyTwist;
    // None (the default): no space dyeing.
    if (!dyeLength.is_none()) o.dyeLength = dyeLength.cast<double>();
    if (!envmap.is_none()) o.envmap = pathOf(envmap, "envmap");
    if (!colours.is_none())
        for (const auto& c : colours.cast<std::vector<std::vector<double>>>()) {
            if (c.size() != 3)
                throw InputError("colours: each colour is (r, g, b) in [0, 1], got " +
                                 std::to_string(c.size()) + " values");
            o.colours.emplace_back(c[0], c[1], c[2]);
        }
    if (!appearances.is_none()) {
        if (!py::isinstance<py::sequence>(appearances) || py::isinstance<py::str>(appearances))
            throw InputError(
                "appearances: expected a list of sRGB colours (\"#rrggbb\" or "
                "(r, g, b) in [0, 1])");
        const py::sequence list = appearances.cast<py::sequence>();
        for (size_t k = 0; k < py::len(list); ++k)
            o.appearances.push_back(srgbArg(list[k], jsonIndexPath("appearances", k)));
    }
    checkOutputsSpareInputs({{"model", o.model}, {"envmap", o.envmap}, {"curves", o.curves}}, {}, {},
                            {{"out", dir}});
    json summary;
    std::vector<std::string> warnings;
    {
        py::gil_scoped_release release;
        const eval::GeneratedScene generated = eval::generateScene(kind, o);
        eval::writeScene(generated, dir);
        summary = eval::sceneSummary(generated, kind, dir, &warnings);
        warnings.insert(warnings.end(), generated.colourWarnings.begin(),
                        generated.colourWarnings.end());
    }
    for (const std::string& w : warnings)
        if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw py::error_already_set();
    return pyFromJson(summary);
}

py::object pyYarnAppearance(const py::object& modelArg, const py::object& appearance,
                            const py::object& cTT) {
    const std::string path = pathOf(modelArg, "model");
    std::optional<Rgb> srgb, fiber;
    if (!appearance.is_none()) srgb = srgbArg(appearance, "appearance");
    if (!cTT.is_none()) fiber = colourArg(cTT, "c_tt");
    json report;
    {
        py::gil_scoped_release release;
        const YarnModel model = readUserJson(path, [&] { return loadYarnModel(path); });
        report = appearanceReport(model, path, srgb, fiber, "appearance", "c_tt");
    }
    return pyFromJson(report);
}

}  // namespace

}  // namespace weft::python

PYBIND11_MODULE(weft, m) {
    using namespace weft;
    using namespace weft::python;

    m.doc() =
        "weft: the neural yarn appearance model (Soh & Montazeri 2024) from Python. "
        "See docs/python.md.";
    m.attr("__version__") = WEFT_VERSION;

    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });

    m.def(
        "presets",
        [] {
            std::vector<std::string> names;
            for (const auto& p : materialPresets()) names.emplace_back(p.name);
            return names;
        },
        "Names of the paper's Table 3 materials.");

    py::class_<FiberBcsdf>(m, "FiberBcsdf",
                           "The fiber BCSDF of Khungurn et al. (2015) in its local frame: tangent "
                           "+x, azimuth in the y-z plane (docs/cli.md, `weft fiber`).")
        .def(py::init([](const py::dict& params) { return FiberBcsdf(fiberParamsOf(params)); }),
             py::arg("params"),
             "From a dict {c_r, c_tt, beta_r_deg, beta_tt_deg, gamma_tt_deg} (every key "
             "required, as the --params JSON).")
        .def_static(
            "preset",
            [](const std::string& name) { return FiberBcsdf(findMaterialPreset(name).fiber); },
            py::arg("name"), "A Table 3 material: fleece, silk, polyester, cotton, gabardine.")
        .def_property_readonly("params",
                               [](const FiberBcsdf& f) { return pyFromJson(f.params().toJson()); })
        .def(
            "eval",
            [](const FiberBcsdf& f, const py::object& wi, const py::object& wo) {
                return evalRows(f, wi, wo);
            },
            py::arg("wi"), py::arg("wo"), "RGB eval(wi, wo), cos(theta_o) included: (n,3).")
        .def(
            "pdf",
            [](const FiberBcsdf& f, const py::object& wi, const py::object& wo) {
                return pdfRows(f, wi, wo);
            },
            py::arg("wi"), py::arg("wo"), "Solid-angle density of sample(): (n,).")
        .def(
            "sample",
            [](const FiberBcsdf& f, const py::object& wi, const py::object& u) {
                return sampleRows(f, wi, u);
            },
            py::arg("wi"), py::arg("u"),
            "One sample per row of u (n,3) in [0,1): dict wo (n,3), weight (n,3), pdf (n,), "
            "lobe (n,) (0 = R, 1 = TT).")
        .def(
            "sample_seeded",
            [](const FiberBcsdf& f, const py::object& wi, const py::object& count,
               const py::object& seed) { return sampleSeeded(f, wi, count, seed); },
            py::arg("wi"), py::arg("count"), py::arg("seed") = 0,
            "The samples of `weft fiber sample --wi WI --count COUNT --seed SEED`.")
        .def(
            "albedo",
            [](const FiberBcsdf& f, const py::object& wiArg) {
                const Rows wi = rowsOf(wiArg, "wi");
                py::array_t<double> out = rgbArray(wi.n, wi.single);
                double* o = out.mutable_data();
                {
                    py::gil_scoped_release release;
                    for (size_t i = 0; i < wi.n; ++i) {
                        const Rgb a = f.albedo(unitRow(wi, i, "wi"));
                        o[3 * i] = a.r, o[3 * i + 1] = a.g, o[3 * i + 2] = a.b;
                    }
                }
                return out;
            },
            py::arg("wi"), "Analytic directional albedo F + (1 - F) C_TT: (n,3).");

    py::class_<PyYarnModel>(m, "YarnModel",
                            "A fitted neural yarn model (model.json) and its yarn BSDF, in the "
                            "yarn frame t = +x, b = +y, n = +z (docs/yarn.md).")
        .def(py::init([](const py::dict& model, bool energyGuard, const std::string& sampling) {
                 const std::string source = "model";
                 const json j = jsonFromPy(model, source);
                 YarnModel ym = readUserJson(source, [&] { return yarnModelFromJson(j, source); });
                 return std::make_unique<PyYarnModel>(std::move(ym), source, energyGuard, sampling);
             }),
             py::arg("model"), py::arg("energy_guard") = true, py::arg("sampling") = "tabulated",
             "From a dict in the model.json layout (docs/model-format.md).")
        .def_static(
            "load",
            [](const py::object& path, bool energyGuard, const std::string& sampling) {
                const std::string p = pathOf(path, "path");
                YarnModel ym = readUserJson(p, [&] { return loadYarnModel(p); });
                return std::make_unique<PyYarnModel>(std::move(ym), p, energyGuard, sampling);
            },
            py::arg("path"), py::arg("energy_guard") = true, py::arg("sampling") = "tabulated",
            "Reads a model.json (weft fit); energy_guard=False is --no-energy-guard.")
        .def_static(
            "from_family",
            [](const py::object& path, const py::dict& yarn, bool energyGuard,
               const std::string& sampling) {
                const std::string p = pathOf(path, "family");
                const YarnPoint point = readUserJson("yarn", [&] {
                    return YarnPoint::fromJson(jsonFromPy(yarn, "yarn"), "yarn", "");
                });
                YarnModel ym =
                    readUserJson(p, [&] { return loadFamilyModel(p).at(point, "yarn"); });
                return std::make_unique<PyYarnModel>(std::move(ym), p, energyGuard, sampling);
            },
            py::arg("family"), py::arg("yarn"), py::arg("energy_guard") = true,
            py::arg("sampling") = "tabulated",
            "The yarn of a family model (weft fit family; docs/family.md) at `yarn`, a dict "
            "{fibers, density, twist, beta_r_deg, beta_tt_deg, gamma_tt_deg, c_r}: what "
            "`weft yarn at` writes. ValueError naming the field outside the family's box.")
        .def(
            "eval",
            [](const PyYarnModel& y, const py::object& wi, const py::object& wo) {
                return evalRows(*y.bsdf, wi, wo);
            },
            py::arg("wi"), py::arg("wo"), "Continuous part R + M of eval(wi, wo): (n,3).")
        .def(
            "pdf",
            [](const PyYarnModel& y, const py::object& wi, const py::object& wo) {
                return pdfRows(*y.bsdf, wi, wo);
            },
            py::arg("wi"), py::arg("wo"), "Density of sample() over the continuous part: (n,).")
        .def(
            "sample",
            [](const PyYarnModel& y, const py::object& wi, const py::object& u) {
                return sampleRows(*y.bsdf, wi, u);
            },
            py::arg("wi"), py::arg("u"),
            "One sample per row of u (n,3) in [0,1): dict wo, weight, pdf (0 for the delta T "
            "lobe), lobe (0 = T, 1 = R, 2 = M).")
        .def(
            "sample_seeded",
            [](const PyYarnModel& y, const py::object& wi, const py::object& count,
               const py::object& seed) { return sampleSeeded(*y.bsdf, wi, count, seed); },
            py::arg("wi"), py::arg("count"), py::arg("seed") = 0,
            "The samples of `weft yarn sample --wi WI --count COUNT --seed SEED`.")
        .def(
            "p_t",
            [](const PyYarnModel& y, const py::object& wiArg) {
                const Rows wi = rowsOf(wiArg, "wi");
                py::array_t<double> out = scalarArray(wi.n);
                double* o = out.mutable_data();
                {
                    py::gil_scoped_release release;
                    for (size_t i = 0; i < wi.n; ++i)
                        o[i] = y.bsdf->transmission(unitRow(wi, i, "wi"));
                }
                return scalarResult(out, wi.single);
            },
            py::arg("wi"), "P(T | wi) of the T network: (n,).")
        .def_property_readonly("t_net",
                               [](const PyYarnModel& y) { return networkDict(y.model.tNet); })
        .def_property_readonly("m_net",
                               [](const PyYarnModel& y) { return networkDict(y.model.mNet); })
        .def_property_readonly(
            "fiber", [](const PyYarnModel& y) { return FiberBcsdf(y.model.fiber); },
            "The fiber BCSDF of the model's material.")
        .def_property_readonly(
            "ablation",
            [](const PyYarnModel& y) { return std::string(yarnAblationName(y.model.ablation)); })
        .def_property_readonly("source", [](const PyYarnModel& y) { return y.source; })
        .def(
            "to_dict", [](const PyYarnModel& y) { return pyFromJson(yarnModelToJson(y.model)); },
            "The model.json document as a dict.")
        .def(
            "save",
            [](const PyYarnModel& y, const py::object& path) {
                saveYarnModel(y.model, pathOf(path, "path"));
            },
            py::arg("path"), "Writes model.json (atomically).");

    m.def(
        "fit_config",
        [](const py::object& config) { return pyFromJson(fitConfigOf(config).toJson()); },
        py::arg("config") = py::none(),
        "The fit configuration in effect (defaults, or a dict / FIT.json path over them), as "
        "`weft fit --print-config`.");

    m.def("gather", &pyGather, py::kw_only(), py::arg("preset") = py::none(),
          py::arg("params") = py::none(), py::arg("fibers") = py::none(),
          py::arg("density") = py::none(), py::arg("twist") = py::none(), py::arg("paths"),
          py::arg("seed") = 0, py::arg("ply_seed") = py::none(),
          py::arg("bins") = std::vector<int>{22, 90, 45, 90}, py::arg("max_depth") = 1000,
          py::arg("threads") = 0, py::arg("segments_per_twist") = 128,
          py::arg("shard") = py::none(), py::arg("any_colour") = false, py::arg("out") = py::none(),
          py::arg("quiet") = true,
          "`weft gather`: the RDM of a ply as a dict of arrays (count, count_t, p_t, rdm_r, "
          "rdm_m, truncated, depth, exit_distance, exit_offset) and stats; out=DIR also writes "
          "the gather "
          "folder. "
          "shard=(k, n): only shard k of n of the paths, as integer sums (count, count_t, "
          "sum_r, sum_m, sum_truncated, sum_exit_distance, sum_exit_offset, depth) for "
          "gather_merge; out=DIR "
          "writes the part. "
          "any_colour=True: colour-blind lobe choice and the recorded paths (paths_bins, "
          "paths_kind, paths_weight) for gather_recolour.");

    m.def("gather_recolour", &gatherRecolour, py::arg("gather"), py::kw_only(), py::arg("c_tt"),
          py::arg("out") = py::none(),
          "`weft gather recolour`: the gather of another fiber colour c_tt=(r, g, b) from a "
          "gather folder written with any_colour=True; returns gather()'s dict (stats has "
          "recoloured_from); out=DIR writes the gather folder.");

    m.def("gather_family", &pyGatherFamily, py::kw_only(), py::arg("points"), py::arg("paths"),
          py::arg("out"), py::arg("box") = py::none(), py::arg("seed") = 0,
          py::arg("bins") = std::vector<int>{11, 45, 15, 30}, py::arg("max_depth") = 1000,
          py::arg("threads") = 0, py::arg("segments_per_twist") = 128,
          py::arg("shard") = py::none(), py::arg("design") = "halton", py::arg("quiet") = true,
          "`weft gather family` (docs/family.md): the yarns of a family, points spread over a "
          "box of yarn parameters (box: a dict in BOX.json's layout or its path; None: the "
          "default box), each an any-colour gather of `paths` walks in out/points/NNNNN, and "
          "out/family.json; shard=(k, n) gathers shard k of n of the points into the same out; "
          "design: 'halton' (uniform) or 'edges' (denser towards the box's faces). "
          "Returns the summary dict.");

    m.def("gather_merge", &gatherMerge, py::arg("parts"), py::kw_only(),
          py::arg("out") = py::none(),
          "`weft gather merge`: the part folders of gather(shard=(k, n), out=...) for k = 0..n-1 "
          "added into one gather, bit for bit the unsharded one; returns gather()'s dict; "
          "out=DIR writes the gather folder.");

    m.def("fit", &pyFit, py::arg("rdm"), py::kw_only(), py::arg("out") = py::none(),
          py::arg("config") = py::none(), py::arg("seed") = 0, py::arg("threads") = py::none(),
          py::arg("ablation") = "none", py::arg("reference") = py::none(),
          py::arg("report") = py::none(), py::arg("colour_range") = py::none(),
          py::arg("colour_functions") = 6, py::arg("quiet") = true,
          "`weft fit`: fits a YarnModel to a gather folder; returns {model, report}. "
          "colour_range=(lo, hi): `weft fit --colour-range`, a model for every C_TT in the "
          "range from a gather made with any_colour=True (colour_functions: K, 2..12); "
          "report['colour'] holds its errors by colour.");

    m.def("curves_info", &pyCurvesInfo, py::arg("path"), py::arg("radius") = py::none(),
          "`weft curves info`: the report of a curve file (.bcc, .txt, .obj) as a dict: counts, "
          "lengths, bounds, the closest contact, the largest radius without overlap and, with "
          "radius=, the overlap at that radius.");

    m.def("scene", &pyScene, py::arg("kind"), py::kw_only(), py::arg("model"), py::arg("out"),
          py::arg("size") = 6, py::arg("radius") = 0.01, py::arg("plies") = 3,
          py::arg("ply_twist") = 0.3, py::arg("width") = 512, py::arg("height") = 512,
          py::arg("spp") = 64, py::arg("envmap") = py::none(), py::arg("colours") = py::none(),
          py::arg("appearances") = py::none(), py::arg("stripe") = py::none(),
          py::arg("dye_length") = py::none(), py::arg("yarn") = py::none(),
          py::arg("curves") = py::none(), py::arg("curve_radius") = py::none(),
          py::arg("view") = "three-quarter", py::arg("floor") = false,
          "`weft scene`: writes the generated scene folder `out` (\"closeup\", \"weave\", "
          "\"knit\", or \"curves\" with curves=FILE framed whole from view=, its radius "
          "curve_radius in the file's units or the largest without overlap; floor=True adds a "
          "floor) and returns its summary dict; colours=[(r, g, b)] colours every yarn, two "
          "colours make a striped knit or a check weave (stripe yarns per stripe, default 2), or "
          "with "
          "dye_length=L space-dyed yarns (the colour alternating every L yarn radii); "
          "appearances=[\"#rrggbb\" or (r, g, b)] instead gives the sRGB colours the yarns should "
          "look (docs/colour.md, \"Colour by appearance\"); with a family model, yarn={fibers, "
          "density, twist, beta_r_deg, beta_tt_deg, gamma_tt_deg, c_r} is the yarn every entry "
          "draws (docs/family.md). Warnings (overlapping yarns, colours a neural render would "
          "refuse) are UserWarnings.");

    m.def("yarn_appearance", &pyYarnAppearance, py::arg("model"), py::kw_only(),
          py::arg("appearance") = py::none(), py::arg("c_tt") = py::none(),
          "`weft yarn appearance`: a colour model's darkest and brightest appearance per "
          "channel, and with appearance=\"#rrggbb\" or (r, g, b) (sRGB) the fiber colour c_tt "
          "that gives it, or with c_tt=(r, g, b) its appearance (docs/colour.md).");

    m.def("render", &pyRender, py::arg("scene"), py::kw_only(), py::arg("mode") = py::none(),
          py::arg("spp") = py::none(), py::arg("seconds") = py::none(), py::arg("threads") = 0,
          py::arg("seed") = py::none(), py::arg("fiber_seed") = py::none(), py::arg("nee") = true,
          py::arg("yarn_sampling") = "tabulated", py::arg("sampler") = py::none(),
          py::arg("base_dir") = py::none(), py::arg("shard") = py::none(), py::arg("quiet") = true,
          py::arg("integrator") = "auto", py::arg("progress") = py::none(),
          py::arg("progress_seconds") = 1.0,
          "`weft render`: a scene file or dict to an (H,W,3) float32 linear RGB image and the "
          "statistics dict; mode (\"neural\", \"fiber\" or \"dual\") draws every yarn so, "
          "over the yarns' own \"mode\" (None: each yarn's, neural where it names none); "
          "shard=(k, n) traces only shard k of n of the spp samples; fiber_seed draws the "
          "fibers in another arrangement (render.fiber_seed). quiet=False shows the "
          "progress on sys.stderr (as Jupyter shows it); integrator (\"auto\", \"path\" or "
          "\"batch\") as `weft render --integrator`, the same image. progress(fraction, image) "
          "is called every progress_seconds (default 1, at least 0.1; between passes) with the "
          "image so far; returning False stops the render early (stats[\"partial\"]). "
          "weft.save_image writes the image.");

    m.def("curves_points", &pyCurvesPoints, py::arg("path"),
          "`weft curves points`: the control points of a curve file as an (n, 4) float64 array "
          "(curve index, x, y, z) in the file's order and units; an (n, 3) colour array in that "
          "order, saved as .npy, is a yarn's vertex_colours (docs/scene-format.md).");
    m.def("save_image", &pySaveImage, py::arg("path"), py::arg("image"), py::kw_only(),
          py::arg("exposure") = 0.0,
          "Write an (H,W,3) linear RGB image (as render returns it): .exr as linear float, "
          ".png as 8-bit sRGB after 2^exposure, clamped; exposure in stops or \"auto\" (the "
          "99th percentile of the luminance to 0.9, as `weft render --exposure auto`). "
          "Written atomically; returns the stops used.");
    m.def("read_image", &pyReadImage, py::arg("path"),
          "Read an .exr, .hdr or .png (decoded from sRGB) as an (H,W,3) float32 linear RGB array.");

    py::class_<PyView>(m, "View",
                       "A live `weft view` page served from this process (weft.view); shown "
                       "inline in a notebook, stopped by stop() or when collected.")
        .def_property_readonly("url", &PyView::url, "The page's address")
        .def("state", &PyView::state, "What the page shows and may choose (a dict)")
        .def("stats", &PyView::stats, "Samples, time per sample, SSIM, errors (a dict)")
        .def("save", &PyView::save, "Save as the page's button does; returns the file names")
        .def("stop", &PyView::stop, "Stop the server and its renders")
        .def("_repr_html_", &PyView::html)
        .def("__repr__", [](const PyView& v) { return "<weft.View " + v.html() + ">"; });
    m.def(
        "view",
        [](const py::object& scene, int port, const std::string& bind, const py::object& out,
           const std::vector<std::string>& models, const py::object& modelsDir, int spp,
           int threads) {
            view::ViewOptions o;
            o.scenePath = pathOf(scene, "scene");
            o.outDir = out.is_none() ? std::string("weft-view") : pathOf(out, "out");
            o.models = models;
            o.presetsDir = view::presetsDir(
                modelsDir.is_none() ? std::string() : pathOf(modelsDir, "models_dir"),
                "models_dir");
            o.sppCap = spp;
            o.threads = threads;
            view::ServerOptions server;
            server.host = bind;
            server.port = port;
            server.validate();
            return std::make_unique<PyView>(o, server);
        },
        py::arg("scene"), py::kw_only(), py::arg("port") = 0, py::arg("bind") = "127.0.0.1",
        py::arg("out") = py::none(), py::arg("models") = std::vector<std::string>{},
        py::arg("models_dir") = py::none(), py::arg("spp") = 0, py::arg("threads") = 0,
        "`weft view`: serve the live page for a scene file from this process and return a "
        "View (its url; in a notebook it shows the page inline). Stops with View.stop().");
    m.def("render_merge", &renderMerge, py::arg("parts"),
          "`weft render merge`: the sample-weighted mean of the PART.exr files (PART.json "
          "beside each) that `weft render --shard K/N` wrote; returns (image, stats).");
}
