#include "ProgramMain.h"

#include <exception>
#include <iostream>
#include <new>

#include "voxfuse/core/Error.h"

namespace voxfuse::app {

int runReportingErrors(const char* program, const std::function<int()>& body) {
    try {
        return body();
    } catch (const Error& e) {
        std::cerr << "\n" << program << ": error: " << e.what() << "\n";
        return 2;
    } catch (const std::bad_alloc&) {
        std::cerr << "\n"
                  << program << ": error: out of memory: the settings ask for more memory than this machine has "
                  << "(larger --voxel-size, smaller --max-blocks or --volume-size, fewer --frames)\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "\n" << program << ": unexpected error: " << e.what() << "\n";
        return 3;
    } catch (...) {
        std::cerr << "\n" << program << ": unexpected error (not a std::exception)\n";
        return 3;
    }
}

}  // namespace voxfuse::app
