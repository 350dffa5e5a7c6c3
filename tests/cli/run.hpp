#pragma once
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

struct RunResult {
  int code = -1;
  std::string out, err;
};

// Runs `pteryla <args>` through the shell; stdout and stderr captured separately.
inline RunResult runPteryla(const std::string& args) {
  const std::string errFile = std::string(PTERYLA_BUILD_DIR) + "/cli_stderr_" + std::to_string(::getpid()) + ".txt";
  const std::string cmd = std::string("\"") + PTERYLA_EXE + "\" " + args + " 2>\"" + errFile + "\"";
  RunResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (FILE* e = fopen(errFile.c_str(), "r")) {
    while ((n = fread(buf.data(), 1, buf.size(), e)) > 0) r.err.append(buf.data(), n);
    fclose(e);
  }
  std::remove(errFile.c_str());
  return r;
}

inline std::string writeTemp(const std::string& name, const std::string& content) {
  const std::string path = std::string(PTERYLA_BUILD_DIR) + "/" + name;
  FILE* f = fopen(path.c_str(), "wb");
  fputs(content.c_str(), f);
  fclose(f);
  return path;
}
