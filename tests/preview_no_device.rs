//! With no Vulkan driver to load, the previewer's device setup fails with one sentence that
//! says what to install (its own test binary: it points the loader at a driver list that does
//! not exist, for this process only).

use wpbgi::preview::device::{Gpu, VulkanError};

#[test]
fn no_driver_says_what_to_install() {
    // Both spellings: older loaders read VK_ICD_FILENAMES, newer ones VK_DRIVER_FILES.
    for var in ["VK_ICD_FILENAMES", "VK_DRIVER_FILES"] {
        // SAFETY: the only test in this binary, before any thread reads the environment.
        unsafe { std::env::set_var(var, "/nonexistent/wpbgi-no-driver.json") };
    }
    let err = match Gpu::new(false) {
        Ok(gpu) => panic!("a device without drivers: {}", gpu.name),
        Err(e) => e,
    };
    assert!(matches!(err, VulkanError::NoDevice), "{err:?}");
    let text = err.to_string();
    assert!(text.contains("mesa-vulkan-drivers"), "{text}");
}
