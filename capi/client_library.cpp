// libshadowtiles_client has no code of its own: it is the client layers' archives linked whole
// (capi/CMakeLists.txt). CMake needs one source to make a library target; this is it.
