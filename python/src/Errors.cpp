// The library's exceptions as Python exceptions carrying the same message:
//   voxfuse.Error (RuntimeError)
//   voxfuse.IoError (voxfuse.Error, OSError): a file or frame cannot be read or written
//   voxfuse.ParseError (voxfuse.IoError): a malformed line of a text file
//   voxfuse.ConfigError (voxfuse.Error, ValueError): settings that cannot work together
//   voxfuse.DeviceError (voxfuse.Error): the GPU or a device call failed

#include "Bindings.h"
#include "voxfuse/core/Error.h"

namespace voxfuse::python {

namespace py = pybind11;

namespace {

PyObject* newException(py::module_& m, const char* name, py::tuple bases, const char* doc) {
    const std::string qualified = std::string("voxfuse.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (!type) throw py::error_already_set();
    m.add_object(name, py::handle(type));  // the module keeps the reference
    return type;
}

}  // namespace

void bindErrors(py::module_& m) {
    static PyObject* error = newException(m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
                                          "Any error VoxFuse reports; the message says what failed and where.");
    static PyObject* io_error = newException(m, "IoError", py::make_tuple(py::handle(error), py::handle(PyExc_OSError)),
                                             "A file or frame cannot be read or written (the message names it).");
    static PyObject* parse_error =
        newException(m, "ParseError", py::make_tuple(py::handle(io_error)),
                     "A malformed line of a text file (the message reads 'file:line: reason').");
    static PyObject* config_error =
        newException(m, "ConfigError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)),
                     "Settings that are out of range or cannot work together.");
    static PyObject* device_error = newException(m, "DeviceError", py::make_tuple(py::handle(error)),
                                                 "The GPU is missing or a device call failed.");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ParseError& e) {
            PyErr_SetString(parse_error, e.what());
        } catch (const IoError& e) {
            PyErr_SetString(io_error, e.what());
        } catch (const ConfigError& e) {
            PyErr_SetString(config_error, e.what());
        } catch (const DeviceError& e) {
            PyErr_SetString(device_error, e.what());
        } catch (const Error& e) {
            PyErr_SetString(error, e.what());
        }
    });
}

}  // namespace voxfuse::python
