# Writes OUT (a C++ source defining sdft::build_config::kRevision) with the checkout's git
# revision, rewriting it only when the revision changed, so a build after a commit relinks but
# recompiles nothing else. Run at every build: cmake -DSRC=... -DOUT=... -P revision.cmake
set(rev "unknown")
find_program(GIT git)
if(GIT AND EXISTS "${SRC}/.git")
    execute_process(COMMAND ${GIT} -C "${SRC}" rev-parse --short=10 HEAD
                    OUTPUT_VARIABLE head OUTPUT_STRIP_TRAILING_WHITESPACE
                    RESULT_VARIABLE rc ERROR_QUIET)
    if(rc EQUAL 0 AND head)
        set(rev "${head}")
        execute_process(COMMAND ${GIT} -C "${SRC}" status --porcelain --untracked-files=no
                        OUTPUT_VARIABLE dirty OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
        if(dirty)
            string(APPEND rev "+")
        endif()
    endif()
endif()
set(text "namespace sdft::build_config { extern const char* const kRevision; const char* const kRevision = \"${rev}\"; }\n")
if(EXISTS "${OUT}")
    file(READ "${OUT}" old)
endif()
if(NOT old STREQUAL text)
    file(WRITE "${OUT}" "${text}")
endif()
