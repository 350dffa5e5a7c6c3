# Installs tests/export/package-lock.json's packages into DST (a build-tree directory) with `npm ci`.
# Where the npm registry cannot be reached (no network, or a TLS-intercepting proxy whose CA the system
# does not trust: seen on a fresh Debian 12 root), this writes DST/registry_unreachable.txt with npm's
# message instead of failing, and export.cli_validate then runs everything but the Khronos validator and
# says so. Any other npm failure fails the test.
find_program(NPM npm)
if(NOT NPM)
  message(FATAL_ERROR "npm not found: install nodejs and npm (tools/bootstrap.sh) to validate glTF exports")
endif()
file(MAKE_DIRECTORY ${DST})
file(REMOVE ${DST}/registry_unreachable.txt)
file(COPY ${SRC}/package.json ${SRC}/package-lock.json DESTINATION ${DST})
execute_process(COMMAND ${NPM} ci --no-audit --no-fund --loglevel=error WORKING_DIRECTORY ${DST}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  string(REGEX MATCH "SELF_SIGNED_CERT|UNABLE_TO_GET_ISSUER_CERT|CERT_|ENOTFOUND|EAI_AGAIN|ECONNREFUSED|ECONNRESET|ETIMEDOUT|ENETUNREACH" network "${err}${out}")
  if(network)
    file(WRITE ${DST}/registry_unreachable.txt "${err}${out}")
    message(WARNING "npm registry unreachable (${network}): the Khronos glTF validator will not run.\n${err}")
    return()
  endif()
  message(FATAL_ERROR "npm ci failed (${rc}) in ${DST}:\n${err}${out}")
endif()
