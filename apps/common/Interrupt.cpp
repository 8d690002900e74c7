#include "Interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

namespace voxfuse::app::interrupt {

namespace {

std::atomic<int> g_signal{0};  // lock-free: safe to touch in a signal handler
char g_first_message[256];
char g_second_message[256];
std::size_t g_first_length = 0, g_second_length = 0;

void say(const char* text, std::size_t length) {
    const ssize_t ignored = ::write(STDERR_FILENO, text, length);
    (void)ignored;
}

// Only async-signal-safe calls here: an atomic, write() and _exit().
void onSignal(int signal_number) {
    // The interrupted thread may be about to read errno (a failed write it reports): write() here
    // must not change it.
    const int saved_errno = errno;
    int none = 0;
    if (g_signal.compare_exchange_strong(none, signal_number)) {
        say(g_first_message, g_first_length);
        errno = saved_errno;
        return;
    }
    say(g_second_message, g_second_length);
    ::_exit(128 + signal_number);
}

void prepareMessage(char* buffer, std::size_t& length, const std::string& text) {
    std::strncpy(buffer, text.c_str(), sizeof g_first_message - 1);
    buffer[sizeof g_first_message - 1] = '\0';
    length = std::strlen(buffer);
}

}  // namespace

void install(const char* program) {
    prepareMessage(g_first_message, g_first_length,
                   std::string("\n") + program +
                       ": interrupted: stopping after this frame and writing the outputs (again to quit at once)\n");
    prepareMessage(g_second_message, g_second_length,
                   std::string("\n") + program + ": interrupted again: quitting now, outputs not written\n");
    struct sigaction action {};
    action.sa_handler = onSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;  // reads and waits in progress go on; the loop checks requested()
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

bool requested() { return g_signal.load() != 0; }

int exitStatus() {
    const int s = g_signal.load();
    return s != 0 ? 128 + s : 0;
}

}  // namespace voxfuse::app::interrupt
